# One CTest smoke run of a fuzz target (tests/fuzz/CMakeLists.txt):
#   cmake -DFUZZER=... -DWORK_DIR=... -DRUNS=... -DMAX_SECONDS=... -DDICTIONARY=...
#         -DGENERATED=... -DSEEDS=... -DREGRESSIONS=... -P run_fuzzer.cmake
# New inputs go to a fresh WORK_DIR/corpus, so that runs do not feed each other and the result
# depends only on the sources, the seeds and the fixed random seed. Findings land in WORK_DIR.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/corpus")
set(inputs "${WORK_DIR}/corpus")
# Every seed and regression input runs first; a missing folder (no regression yet) is skipped.
foreach(dir IN ITEMS "${GENERATED}" "${SEEDS}" "${REGRESSIONS}")
  if(IS_DIRECTORY "${dir}")
    list(APPEND inputs "${dir}")
  endif()
endforeach()
execute_process(
  COMMAND ${CMAKE_COMMAND} -E env PALOVERDE_FUZZ_SCRATCH=${WORK_DIR}/scratch
          "${FUZZER}" -runs=${RUNS} -max_total_time=${MAX_SECONDS} -seed=1 -timeout=10
          -rss_limit_mb=2048 -malloc_limit_mb=1024 -dict=${DICTIONARY} -artifact_prefix=${WORK_DIR}/
          -print_final_stats=1 ${inputs}
  RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "${FUZZER} found a problem (exit ${result}); the input is in ${WORK_DIR} "
                      "(crash-*, leak-*, oom-* or timeout-*). Fix it, then add the input to "
                      "tests/fuzz/regressions/ (docs/robustness.md).")
endif()
