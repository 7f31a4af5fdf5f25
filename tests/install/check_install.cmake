# Installs the build tree into a scratch prefix, then configures, builds and runs a downstream
# project against it with find_package(Paloverde CONFIG).
file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "failed (${code}): ${ARGV}\n${out}")
  endif()
  message(STATUS "${out}")
endfunction()
run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
run(${CMAKE_COMMAND} -S "${SOURCE_DIR}/tests/install/consumer" -B "${WORK_DIR}/consumer"
    -G "${GENERATOR}" -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build "${WORK_DIR}/consumer")
run(${CMAKE_COMMAND} -E env LD_LIBRARY_PATH=${prefix}/lib "${WORK_DIR}/consumer/consumer")
# The Python package, where the build has one: imported from the prefix by the python3 it was built for.
if(PYTHON)
  file(GLOB package_dirs "${prefix}/lib/python3*/dist-packages")
  if(NOT package_dirs)
    message(FATAL_ERROR "the Python package was not installed under ${prefix}/lib/python3*/dist-packages")
  endif()
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${package_dirs} LD_LIBRARY_PATH=${prefix}/lib
      "${PYTHON}" -c "import paloverde; print('paloverde', paloverde.Mesh)")
endif()
