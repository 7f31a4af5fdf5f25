// Every shared mesh through every format that can hold it: what is read back is what was
// written (coordinates bit for bit, connectivity, fixed flags where the format stores them).
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>

#include <sys/stat.h>

#include <fstream>
#include <iterator>
#include <thread>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;

namespace {
const std::vector<std::string> kMeshes = {
    "mesquite/tets/tet_1.vtk",          "mesquite/tets/two_tets.vtk",     "mesquite/tets/two_tets_shape.vtk",
    "mesquite/tets/tet_2_with_bound.vtk", "mesquite/tets/tet_4_tangled.vtk", "mesquite/tets/tire.vtk",
    "mesquite/tets/cube-clip-5.vtk",    "mesquite/tets/flat-tet-sphere.vtk", "mesquite/tets/cub_wedge_like.vtk",
    "mesquite/tris/equil_tri.vtk",      "mesquite/tris/tri_5_xz.vtk",     "mesquite/tris/tangled_tri.vtk",
    "mesquite/tris/bad_circle_tri.vtk", "mesquite/tris/shashkov.vtk",     "mesquite/tris/tri_20258.vtk",
    "stellar/house2.node",              "tetwild/armadillo.mesh",         "tetwild/octopus-vol.mesh"};

struct Target {
    const char* name;
    pv::Encoding encoding;
    bool keeps_fixed;
};
const Target kTargets[] = {{"a.vtk", pv::Encoding::Ascii, true},  {"b.vtk", pv::Encoding::Binary, true},
                           {"c.vtu", pv::Encoding::Ascii, true},  {"d.vtu", pv::Encoding::Binary, true},
                           {"e.msh", pv::Encoding::Ascii, true},  {"f.msh", pv::Encoding::Binary, true},
                           {"g.mesh", pv::Encoding::Ascii, false}};
}  // namespace

BOOST_AUTO_TEST_SUITE(all_formats)

BOOST_DATA_TEST_CASE(shared_meshes_round_trip_through_every_format, bdata::make(kMeshes), name) {
    const auto original = pv::read_mesh(pv::test::shared_data(name));
    const auto& mesh = original.mesh;
    const pv::test::ScratchDir dir("all_formats");
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(name << " -> " << target.name) {
            pv::WriteOptions options;
            options.encoding = target.encoding;
            pv::write_mesh(dir / target.name, mesh, options);
            const auto copy = pv::read_mesh(dir / target.name);
            BOOST_TEST((copy.mesh.kind() == mesh.kind()));
            BOOST_TEST_REQUIRE(copy.mesh.num_vertices() == mesh.num_vertices());
            BOOST_TEST_REQUIRE(copy.mesh.num_elements() == mesh.num_elements());
            BOOST_TEST(std::equal(copy.mesh.coordinates().begin(), copy.mesh.coordinates().end(),
                                  mesh.coordinates().begin()));
            BOOST_TEST(std::equal(copy.mesh.connectivity().begin(), copy.mesh.connectivity().end(),
                                  mesh.connectivity().begin()));
            if (target.keeps_fixed || !original.fixed_from_file)
                BOOST_TEST(std::equal(copy.mesh.fixed().begin(), copy.mesh.fixed().end(), mesh.fixed().begin()));
        }
    }
}

// A file of the mirror convention (corners 2 and 3 of every tet swapped) is flipped on reading in
// every format, and what is written from it has the file's order again.
BOOST_AUTO_TEST_CASE(a_mirrored_file_is_flipped_on_reading_and_written_back_as_it_was) {
    const auto original = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const auto mirror = pv::test::mirrored(original);
    const auto swapped = mirror.connectivity();
    const pv::test::ScratchDir dir("mirrored_formats");
    pv::ReadOptions as_is;
    as_is.orientation = pv::OrientationMode::AsIs;
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(target.name) {
            pv::WriteOptions options;
            options.encoding = target.encoding;
            pv::write_mesh(dir / target.name, mirror, options);
            const auto read = pv::read_mesh(dir / target.name);
            BOOST_TEST(read.orientation.flipped);
            BOOST_TEST(read.mesh.elements_flipped());
            BOOST_TEST(std::equal(read.mesh.connectivity().begin(), read.mesh.connectivity().end(),
                                  original.connectivity().begin(), original.connectivity().end()));
            BOOST_TEST(pv::count_orientations(read.mesh).inverted == 0);
            BOOST_TEST(pv::count_orientations(pv::read_mesh(dir / target.name, as_is).mesh).inverted ==
                       original.num_elements());
            const std::string again = std::string("again_") + target.name;
            pv::write_mesh(dir / again, read.mesh, options);
            const auto written = pv::read_mesh(dir / again, as_is).mesh;
            BOOST_TEST(std::equal(written.connectivity().begin(), written.connectivity().end(), swapped.begin(),
                                  swapped.end()));
        }
    }
}


// Regular files are mapped; a pipe cannot be, and is read to its end instead: the same mesh either
// way, in every format. A directory is refused by name.
BOOST_AUTO_TEST_CASE(a_mesh_read_through_a_pipe_is_the_mesh_read_from_its_file) {
    const auto mesh = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const pv::test::ScratchDir dir("piped_formats");
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(target.name) {
            pv::WriteOptions options;
            options.encoding = target.encoding;
            pv::write_mesh(dir / target.name, mesh, options);
            std::ifstream file(dir / target.name, std::ios::binary);
            const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
            const auto pipe = dir / (std::string("pipe_") + target.name);
            BOOST_TEST_REQUIRE(::mkfifo(pipe.c_str(), 0600) == 0);
            std::thread writer([&] { std::ofstream(pipe, std::ios::binary) << bytes; });
            const auto piped = pv::read_mesh(pipe);
            writer.join();
            const auto direct = pv::read_mesh(dir / target.name);
            BOOST_TEST(bytes.size() > 1000u);
            BOOST_TEST_REQUIRE(piped.mesh.num_elements() == mesh.num_elements());
            BOOST_TEST(std::equal(piped.mesh.coordinates().begin(), piped.mesh.coordinates().end(),
                                  direct.mesh.coordinates().begin(), direct.mesh.coordinates().end()));
            BOOST_TEST(std::equal(piped.mesh.connectivity().begin(), piped.mesh.connectivity().end(),
                                  direct.mesh.connectivity().begin(), direct.mesh.connectivity().end()));
        }
    }
    std::filesystem::create_directory(dir / "folder.vtk");
    BOOST_CHECK_EXCEPTION(pv::read_mesh(dir / "folder.vtk"), pv::FileError, [](const pv::FileError& e) {
        return std::string(e.what()).find("folder.vtk") != std::string::npos;
    });
}

BOOST_AUTO_TEST_SUITE_END()
