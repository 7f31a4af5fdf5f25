// The public headers of the layers above the parallel one (solvers, config runs, wrappers) and
// those below it compile without <mpi.h>: a program that never runs distributed does not see
// MPI. (distributed_mesh.hpp and the MPI examples are where it starts.)
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/config/config.hpp"
#include "paloverde/config/registry.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh_interface.hpp"
#include "paloverde/mesh/openmesh_adapter.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/instruction_queue.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/solvers/summary.hpp"
#include "paloverde/solvers/termination.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"
#include "paloverde/wrappers.hpp"
#include <boost/test/unit_test.hpp>

#ifdef MPI_VERSION
#error "<mpi.h> reached through a public header that should not need it"
#endif

BOOST_AUTO_TEST_SUITE(public_headers)

// The check is the #error above, at compile time; this case records that it ran.
BOOST_AUTO_TEST_CASE(reach_no_mpi) { BOOST_TEST(true); }

BOOST_AUTO_TEST_SUITE_END()
