// The `paloverde` command line end to end: output, exit codes, and clear errors for bad input.
#include <algorithm>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "paloverde/io/mesh_io.hpp"
#include "support/cell_meshes.hpp"
#include "support/solver_checks.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
using pv::test::run_cli;

namespace {
std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }
std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}
bool has(const std::string& text, const std::string& word) { return text.find(word) != std::string::npos; }
}  // namespace

BOOST_AUTO_TEST_SUITE(cli)

BOOST_AUTO_TEST_CASE(quality_json_has_the_documented_keys) {
    const auto mesh = pv::test::shared_data("mesquite/tets/cub_wedge_like.vtk");
    const auto result = run_cli("quality --json " + quoted(mesh));
    BOOST_TEST_REQUIRE(result.exit_code == 0);
    const auto j = nlohmann::json::parse(result.output);
    BOOST_TEST(j["vertices"].get<int>() == 21156);
    BOOST_TEST(j["elements"].get<int>() == 112393);
    BOOST_TEST(j["inverted"].get<int>() == 0);
    for (const char* metric : {"aspect_ratio", "mean_ratio", "min_dihedral_deg"})
        for (const char* stat : {"min", "max", "mean", "rms"}) BOOST_TEST(j["metrics"][metric].contains(stat));
    BOOST_TEST(std::abs(j["metrics"]["min_dihedral_deg"]["movable"]["min"].get<double>() - 6.10) < 0.01);
}

// A surface mesh (a bowl of 4 x 4 vertices, one inner vertex off the grid): `quality` rates its
// triangles about the surface's normals, and improve smooths it on itself.
BOOST_AUTO_TEST_CASE(quality_and_improve_take_a_surface) {
    const pv::test::ScratchDir dir("cli_surface");
    std::string text = "# vtk DataFile Version 3.0\nbowl\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 16 double\n";
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            const double x = i * 4 + j == 5 ? 1.3 : i, y = i * 4 + j == 5 ? 0.7 : j;
            text += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(0.2 * (x * x + y * y)) + "\n";
        }
    std::string types;
    text += "CELLS 18 72\n";
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int a = i * 4 + j, b = a + 4;
            text += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(b + 1) + "\n3 " +
                    std::to_string(a) + " " + std::to_string(b + 1) + " " + std::to_string(a + 1) + "\n";
            types += "5\n5\n";
        }
    pv::test::write_file(dir / "bowl.vtk", text + "CELL_TYPES 18\n" + types);
    const auto quality = run_cli("quality " + quoted(dir / "bowl.vtk"));
    BOOST_TEST_REQUIRE(quality.exit_code == 0, quality.output);
    BOOST_TEST(has(quality.output, "a surface: each triangle rated about the surface's normal"), quality.output);
    const auto improved = run_cli("improve " + quoted(dir / "bowl.vtk") + " -o " + quoted(dir / "out.vtk"));
    BOOST_TEST(improved.exit_code == 0, improved.output);
    BOOST_TEST(has(improved.output, "sliding vertices moved"), improved.output);
    const auto after = pv::read_mesh(dir / "out.vtk").mesh;
    BOOST_TEST(after.point(5) != pv::read_mesh(dir / "bowl.vtk").mesh.point(5));  // the inner vertex moved
}

// --domain: a sphere's vertices end on the sphere given, to rounding; a sphere the mesh is not on,
// and a shape that is no shape, are refused naming what to change, and nothing is written.
BOOST_AUTO_TEST_CASE(improve_keeps_a_surface_on_its_domain) {
    const pv::test::ScratchDir dir("cli_domain");
    pv::write_mesh(dir / "ball.vtk", pv::test::sphere(12, 8, 0.3, {1.0, 2.0, 3.0}, 2.0));
    const std::string in = "improve " + quoted(dir / "ball.vtk") + " -o " + quoted(dir / "out.vtk");
    const auto improved = run_cli(in + " --domain '{shape: sphere, point: [1, 2, 3], radius: 2}'");
    BOOST_TEST_REQUIRE(improved.exit_code == 0, improved.output);
    const auto after = pv::read_mesh(dir / "out.vtk").mesh;
    for (pv::VertexId v = 0; v < after.num_vertices(); ++v) {
        const auto p = after.point(v);
        BOOST_TEST(std::abs(std::hypot(p[0] - 1.0, p[1] - 2.0, p[2] - 3.0) - 2.0) < 1e-14);
    }
    const auto off = run_cli(in.substr(0, in.find(" -o ")) + " -o " + quoted(dir / "off.vtk") +
                             " --domain '{shape: sphere, point: [1, 2, 3], radius: 2.5}'");
    BOOST_TEST(off.exit_code == 1, off.output);
    BOOST_TEST(has(off.output, "ball.vtk"), off.output);
    BOOST_TEST(has(off.output, "lies 0.5 off the sphere"), off.output);
    BOOST_TEST(!std::filesystem::exists(dir / "off.vtk"));
    const auto cone = run_cli(in + " --domain '{shape: cone}'");
    BOOST_TEST(cone.exit_code == 2, cone.output);
    BOOST_TEST(has(cone.output, "surface.domain.shape: unknown value 'cone'"), cone.output);
}

BOOST_AUTO_TEST_CASE(improve_untangles_writes_history_and_json_and_exits_zero) {
    const pv::test::ScratchDir dir("cli_improve");
    const auto input = pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk");
    const auto result = run_cli("improve " + quoted(input) + " -o " + quoted(dir / "out.vtu") + " --history " +
                                quoted(dir / "h.csv") + " --summary " + quoted(dir / "s.json"));
    BOOST_TEST_INFO(result.output);
    BOOST_TEST_REQUIRE(result.exit_code == 0);
    BOOST_TEST(pv::read_mesh(dir / "out.vtu").mesh.num_elements() == 408);
    const auto summary = nlohmann::json::parse(read_text(dir / "s.json"));
    BOOST_TEST(summary["inverted_before"].get<int>() == 9);
    BOOST_TEST(summary["inverted_after"].get<int>() == 0);
    BOOST_TEST(has(read_text(dir / "h.csv"), "iteration,phase,worst_quality"));
    const auto after = run_cli("quality --json " + quoted(dir / "out.vtu"));
    BOOST_TEST(nlohmann::json::parse(after.output)["inverted"].get<int>() == 0);
}

BOOST_AUTO_TEST_CASE(improve_method_selects_the_solver) {
    const pv::test::ScratchDir dir("cli_method");
    const auto input = pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk");
    for (const std::string method : {"global", "local", "smart-laplace", "laplace"}) {
        const auto result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "out.vtk") + " --method " +
                                    method + " --iterations 5 --summary " + quoted(dir / "s.json"));
        BOOST_TEST_INFO(method << ": " << result.output);
        const auto summary = nlohmann::json::parse(read_text(dir / "s.json"));
        std::string name = method == "smart-laplace" ? "smart_laplace" : method;
        BOOST_TEST(summary["solver"].get<std::string>() == name);
        // Only the untangling methods succeed on a tangled mesh.
        if (method == "global" || method == "local") {
            BOOST_TEST(result.exit_code == 0);
            BOOST_TEST(summary["inverted_after"].get<int>() == 0);
        } else {
            BOOST_TEST(result.exit_code != 0);
        }
    }
    BOOST_TEST(run_cli("improve " + quoted(input) + " -o " + quoted(dir / "x.vtk") + " --method simplex").exit_code == 2);
}

BOOST_AUTO_TEST_CASE(a_target_that_is_not_reached_exits_three) {
    const pv::test::ScratchDir dir("cli_target");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    const auto result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "out.vtk") +
                                " --iterations 3 --target 0.99");
    BOOST_TEST(result.exit_code == 3);
}

BOOST_AUTO_TEST_CASE(bad_input_gives_a_clear_message_and_a_nonzero_exit) {
    const pv::test::ScratchDir dir("cli_bad");
    pv::test::write_file(dir / "truncated.vtk",
                         "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0");
    pv::test::write_file(dir / "nan.vtk",
                         "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 "
                         "0\n0 nan 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n");
    pv::test::write_file(dir / "range.vtk",
                         "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 "
                         "0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 9\nCELL_TYPES 1\n10\n");
    pv::test::write_file(dir / "empty.vtk", "");
    struct Case {
        std::string file, words;
    };
    for (const Case& c : {Case{"missing.vtk", "no such file"}, Case{"truncated.vtk", "truncated.vtk:5"},
                          Case{"nan.vtk", "nan.vtk:8"}, Case{"range.vtk", "9"}, Case{"empty.vtk", "empty.vtk"},
                          Case{"mesh.xyz", "extension"}}) {
        const auto result = run_cli("quality " + quoted(dir / c.file));
        BOOST_TEST_CONTEXT(c.file << ": " << result.output) {
            BOOST_TEST(result.exit_code == 1);
            BOOST_TEST(has(result.output, c.words));
            BOOST_TEST(!has(result.output, "terminate"));
        }
    }
}

BOOST_AUTO_TEST_CASE(a_failed_write_keeps_the_previous_output) {
    const pv::test::ScratchDir dir("cli_atomic");
    const auto input = pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk");
    pv::test::write_file(dir / "previous.msh", "keep me");
    // An impossible option fails before anything is written.
    auto result = run_cli("improve " + quoted(input) + " -o " + quoted(dir / "previous.msh") + " --barrier-shrink 7");
    BOOST_TEST(result.exit_code == 2);
    BOOST_TEST(has(result.output, "barrier_shrink"));
    BOOST_TEST(read_text(dir / "previous.msh") == "keep me");
    // So does an output directory that does not exist, leaving no partial file anywhere.
    result = run_cli("convert " + quoted(input) + " " + quoted(dir / "no" / "such" / "dir.vtk"));
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(!std::filesystem::exists(dir / "no"));
}

// Targets (docs/targets.md): kept factors, a reference with the input's connectivity, clear errors.
BOOST_AUTO_TEST_CASE(improve_keeps_what_it_is_told_and_refuses_what_it_does_not_know) {
    const pv::test::ScratchDir dir("cli_targets");
    const auto input = pv::test::shared_data("mesquite/hexes/cub_fru.vtk");
    auto result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "x.vtk") + " --keep size,colour");
    BOOST_TEST(result.exit_code == 2);
    BOOST_TEST(has(result.output, "colour"), result.output);
    BOOST_TEST(has(result.output, "size, orientation, aspect, skew, all"), result.output);

    const auto other = pv::test::shared_data("mesquite/hexes/hexes_4by2by2.vtk");
    result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "x.vtk") + " --reference " + quoted(other));
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "hexes_4by2by2.vtk"), result.output);
    BOOST_TEST(has(result.output, "connectivity"), result.output);
    BOOST_TEST(!std::filesystem::exists(dir / "x.vtk"));

    // The default run keeps the cells' aspect: the summary's scaled Jacobian never falls.
    result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "out.vtk") + " --print-config");
    BOOST_TEST_REQUIRE(result.exit_code == 0);
    BOOST_TEST(has(result.output, "keep: [auto]"), result.output);
    result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "out.vtk") + " --keep size,aspect --print-config");
    BOOST_TEST(has(result.output, "shape_size"), result.output);
    // A reference equal to the input, every factor from it: nothing needs to move.
    result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "same.vtk") + " --reference " + quoted(input) +
                     " --summary " + quoted(dir / "s.json"));
    BOOST_TEST_INFO(result.output);
    BOOST_TEST_REQUIRE(result.exit_code == 0);
    const auto summary = nlohmann::json::parse(read_text(dir / "s.json"));
    BOOST_TEST(std::abs(summary["worst_before"].get<double>() - 1.0) < 1e-9);
    // Asking the reference for the aspect overrides the default that keeps a cell's own.
    result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "same.vtk") + " --reference " + quoted(input) +
                     " --set 'targets.from_reference=[size,aspect,skew]' --iterations 1");
    BOOST_TEST(result.exit_code == 0, result.output);
}

// Morphing (docs/morphing.md): a point field moves the boundary, the interior follows; no motion
// hands the input back bit for bit; a field that is missing or is not a displacement is refused.
BOOST_AUTO_TEST_CASE(morph_moves_the_boundary_by_the_field_and_brings_the_interior_along) {
    const pv::test::ScratchDir dir("cli_morph");
    const auto source = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk"));
    const pv::Mesh& mesh = source.mesh;
    auto with_field = [&](const std::string& name, int components, auto value) {
        pv::Field f{"displacement", components, {}};
        for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
            for (int c = 0; c < components; ++c) f.values.push_back(value(v, c));
        pv::write_mesh(dir / name, mesh, pv::WriteOptions{}, std::vector<pv::Field>{f});
        return dir / name;
    };
    const auto still = with_field("still.vtk", 3, [](pv::VertexId, int) { return 0.0; });
    auto result = run_cli("morph -q " + quoted(still) + " -o " + quoted(dir / "still_out.vtk") + " --displacement displacement");
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    const auto in = pv::read_mesh(still), back = pv::read_mesh(dir / "still_out.vtk");
    BOOST_TEST(std::equal(back.mesh.coordinates().begin(), back.mesh.coordinates().end(), in.mesh.coordinates().begin(),
                          in.mesh.coordinates().end()));

    // The whole boundary turned by 15 degrees about the tire's axis (z) through its centre.
    double centre[3] = {0.0, 0.0, 0.0};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        for (int c = 0; c < 3; ++c) centre[c] += mesh.coordinates()[3 * v + c] / mesh.num_vertices();
    const double a = 15.0 * 3.14159265358979 / 180.0;
    auto turn = [&](pv::VertexId v, int c) {
        const double x = mesh.coordinates()[3 * v] - centre[0], y = mesh.coordinates()[3 * v + 1] - centre[1];
        return c == 0 ? std::cos(a) * x - std::sin(a) * y - x : c == 1 ? std::sin(a) * x + std::cos(a) * y - y : 0.0;
    };
    const auto turned = with_field("turned.vtk", 3, turn);
    result = run_cli("morph -q " + quoted(turned) + " -o " + quoted(dir / "turned_out.vtk") +
                     " --displacement displacement --summary " + quoted(dir / "s.json"));
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    const auto summary = nlohmann::json::parse(read_text(dir / "s.json"));
    BOOST_TEST(summary["inverted_before"].get<long>() > 0);
    BOOST_TEST(summary["inverted_after"].get<long>() == 0);
    const auto out = pv::read_mesh(dir / "turned_out.vtk");
    BOOST_TEST(!out.point_field("displacement"));  // spent, not written to move the mesh again
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        if (!mesh.fixed()[static_cast<std::size_t>(v)]) continue;
        for (int c = 0; c < 3; ++c)
            BOOST_TEST(out.mesh.coordinates()[3 * v + c] == mesh.coordinates()[3 * v + c] + turn(v, c));
    }

    // What --keep names comes from the input as read (the reference), not from the moved mesh.
    result = run_cli("morph -q " + quoted(turned) + " -o " + quoted(dir / "kept.vtk") +
                     " --displacement displacement --keep orientation --summary " + quoted(dir / "k.json"));
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    BOOST_TEST(nlohmann::json::parse(read_text(dir / "k.json"))["inverted_after"].get<long>() == 0);
    result = run_cli("morph -q " + quoted(turned) + " -o " + quoted(dir / "x.vtk") + " --displacement velocity");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "no point field 'velocity'"), result.output);
    BOOST_TEST(has(result.output, "displacement"), result.output);
    const auto scalar = with_field("scalar.vtk", 1, [](pv::VertexId, int) { return 0.0; });
    result = run_cli("morph -q " + quoted(scalar) + " -o " + quoted(dir / "x.vtk") + " --displacement displacement");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "has 1 components"), result.output);
    const auto broken = with_field("nan.vtk", 3, [](pv::VertexId v, int c) { return v == 7 && c == 1 ? std::nan("") : 0.0; });
    result = run_cli("morph -q " + quoted(broken) + " -o " + quoted(dir / "x.vtk") + " --displacement displacement");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "not finite at vertex 7"), result.output);
    // The displaced input is its own reference: another is refused.
    std::ofstream(dir / "both.yaml") << "input: {mesh: '" << turned.string() << "', displacement: displacement}\n"
                                     << "targets: {reference: '" << turned.string() << "'}\noutput: {mesh: '"
                                     << (dir / "x.vtk").string() << "'}\n";
    result = run_cli("run " + quoted(dir / "both.yaml"));
    BOOST_TEST(result.exit_code == 2);
    BOOST_TEST(has(result.output, "its own reference"), result.output);
    BOOST_TEST(!std::filesystem::exists(dir / "x.vtk"));
}

// The median volume of a tetrahedral mesh's elements right of x = 0.5 over that of those left of it.
double right_over_left(const pv::Mesh& m) {
    std::vector<double> left, right;
    for (pv::ElementId e = 0; e < m.num_elements(); ++e) {
        const auto c = m.element(e);
        double x[4][3];
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 3; ++k) x[i][k] = m.coordinates()[3 * c[i] + k];
        double a[3], b[3], d[3];
        for (int k = 0; k < 3; ++k) a[k] = x[1][k] - x[0][k], b[k] = x[2][k] - x[0][k], d[k] = x[3][k] - x[0][k];
        const double volume = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
        const double centre = 0.25 * (x[0][0] + x[1][0] + x[2][0] + x[3][0]);
        (centre < 0.5 ? left : right).push_back(std::abs(volume));
    }
    auto median = [](std::vector<double>& v) {
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    return median(right) / median(left);
}

// A size field (docs/targets.md): elements move toward the sizes it asks for; a field that is missing, not one value per point or not a length,
// or a size given twice, is refused.
BOOST_AUTO_TEST_CASE(a_size_field_sizes_the_elements) {
    const pv::test::ScratchDir dir("cli_size_field");
    pv::Mesh mesh = pv::test::cube_grid(6, pv::test::Fill::Tetrahedra);
    // Edges 1.4 times the grid's on the left half, 0.7 times on the right.
    pv::Field h{"h", 1, {}}, wrong{"hh", 3, {}};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        h.values.push_back((mesh.coordinates()[3 * v] < 0.5 ? 1.4 : 0.7) / 6.0);
        wrong.values.insert(wrong.values.end(), {1.0, 1.0, 1.0});
    }
    pv::write_mesh(dir / "in.vtu", mesh, pv::WriteOptions{}, std::vector<pv::Field>{h, wrong});
    auto result = run_cli("improve -q " + quoted(dir / "in.vtu") + " -o " + quoted(dir / "out.vtu") + " --size-field h");
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    // Median element volume on the right over that on the left: 1 in the input (a uniform grid).
    // The solver raises the worst elements against their targets, which here are the ones asked
    // to shrink: those on the right, boundary-fixed on three sides, shrink; the left holds.
    BOOST_TEST(std::abs(right_over_left(mesh) - 1.0) < 1e-9);
    const auto out = pv::read_mesh(dir / "out.vtu");
    BOOST_TEST(right_over_left(out.mesh) < 0.9);
    BOOST_TEST(out.point_field("h"));  // a size field is kept with the output
    result = run_cli("improve -q " + quoted(dir / "in.vtu") + " -o " + quoted(dir / "x.vtu") + " --size-field size");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST((has(result.output, "no point field 'size'") && has(result.output, "h, hh")), result.output);
    result = run_cli("improve -q " + quoted(dir / "in.vtu") + " -o " + quoted(dir / "x.vtu") + " --size-field hh");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "3 components"), result.output);
    result = run_cli("improve -q " + quoted(dir / "in.vtu") + " -o " + quoted(dir / "x.vtu") + " --size-field h --keep size");
    BOOST_TEST(result.exit_code == 2);
    BOOST_TEST(has(result.output, "size_field"), result.output);
    h.values[5] = 0.0;
    pv::write_mesh(dir / "zero.vtu", mesh, pv::WriteOptions{}, std::vector<pv::Field>{h});
    result = run_cli("improve -q " + quoted(dir / "zero.vtu") + " -o " + quoted(dir / "x.vtu") + " --size-field h");
    BOOST_TEST(result.exit_code == 1);
    BOOST_TEST(has(result.output, "vertex 5"), result.output);
    BOOST_TEST(!std::filesystem::exists(dir / "x.vtu"));
}

BOOST_AUTO_TEST_CASE(a_metric_field_shapes_and_sizes_the_elements) {
    const pv::test::ScratchDir dir("cli_metric_field");
    pv::Mesh mesh = pv::test::cube_grid(6, pv::test::Fill::Tetrahedra);
    // Edges 1.4 times the grid's on the left half, 0.7 times on the right (M = I / h^2), as six
    // values and as the whole matrix; and fields that are not metrics.
    pv::Field six{"m", 6, {}}, nine{"m9", 9, {}}, three{"m3", 3, {}}, skewed{"ms", 9, {}}, negative{"mn", 6, {}};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const double h = (mesh.coordinates()[3 * v] < 0.5 ? 1.4 : 0.7) / 6.0, m = 1.0 / (h * h);
        six.values.insert(six.values.end(), {m, m, m, 0.0, 0.0, 0.0});
        nine.values.insert(nine.values.end(), {m, 0.0, 0.0, 0.0, m, 0.0, 0.0, 0.0, m});
        three.values.insert(three.values.end(), {m, m, m});
        skewed.values.insert(skewed.values.end(), {m, 0.1 * m, 0.0, 0.0, m, 0.0, 0.0, 0.0, m});
        negative.values.insert(negative.values.end(), {m, m, v == 7 ? -m : m, 0.0, 0.0, 0.0});
    }
    pv::write_mesh(dir / "in.vtu", mesh, pv::WriteOptions{}, std::vector<pv::Field>{six, nine, three, skewed, negative});
    const std::string run = "improve -q " + quoted(dir / "in.vtu") + " --threads 1 -o ";
    auto result = run_cli(run + quoted(dir / "six.vtu") + " --metric-field m");
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    result = run_cli(run + quoted(dir / "nine.vtu") + " --metric-field m9");
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    const auto out = pv::read_mesh(dir / "six.vtu");
    BOOST_TEST(right_over_left(out.mesh) < 0.9);  // as with the size field of the same lengths
    BOOST_TEST(out.point_field("m"));              // kept with the output
    const auto from_nine = pv::read_mesh(dir / "nine.vtu");
    BOOST_TEST(std::ranges::equal(out.mesh.coordinates(), from_nine.mesh.coordinates()));
    for (const auto& [field, words, code] : {std::tuple{"m3", "3 components", 1}, std::tuple{"ms", "not symmetric at vertex 0", 1},
                                             std::tuple{"mn", "vertex 7", 1}, std::tuple{"none", "no point field 'none'", 1}}) {
        result = run_cli(run + quoted(dir / "x.vtu") + " --metric-field " + field);
        BOOST_TEST(result.exit_code == code, field);
        BOOST_TEST(has(result.output, words), result.output);
    }
    result = run_cli(run + quoted(dir / "x.vtu") + " --metric-field m --keep size");
    BOOST_TEST(result.exit_code == 2);
    BOOST_TEST(has(result.output, "metric_field"), result.output);
    BOOST_TEST(!std::filesystem::exists(dir / "x.vtu"));
}

BOOST_AUTO_TEST_CASE(bad_usage_exits_two) {
    BOOST_TEST(run_cli("").exit_code == 2);
    BOOST_TEST(run_cli("frobnicate").exit_code == 2);
    BOOST_TEST(run_cli("improve").exit_code == 2);
    BOOST_TEST(run_cli("quality --help").exit_code == 0);
}

// The help and the quality report name the cell types the program handles, not only simplices.
BOOST_AUTO_TEST_CASE(help_and_quality_name_the_cell_types) {
    const auto help = run_cli("--help");
    BOOST_TEST(help.exit_code == 0);
    BOOST_TEST_INFO(help.output);
    BOOST_TEST(!has(help.output, "tetrahedral and triangle meshes"));
    for (const char* type : {"tetrahedra", "hexahedra", "wedges", "pyramids", "triangles", "quadrilaterals"})
        BOOST_TEST(has(help.output, type), type);
    struct Case {
        std::string mesh, words;
    };
    for (const Case& c : {Case{"tets/tet_4_tangled.vtk", ": tetrahedron mesh; "},
                          Case{"hexes/hexes_4by2by2.vtk", ": hexahedron mesh; "},
                          Case{"quads/quads_4by2.vtk", ": quadrilateral mesh; "},
                          Case{"mixed/mixed-hex-pyr-tet.vtk", ": mixed mesh: 445 tetrahedra, 305 hexahedra, 190 pyramids; "},
                          Case{"mixed/hybrid_3quad_1tri_tangled.vtk", ": mixed mesh: 1 triangle, 3 quadrilaterals; "}}) {
        const auto result = run_cli("quality " + quoted(pv::test::shared_data("mesquite/" + c.mesh)));
        BOOST_TEST_CONTEXT(c.mesh << ": " << result.output) {
            BOOST_TEST(result.exit_code == 0);
            BOOST_TEST(has(result.output, c.words));
        }
    }
}

BOOST_AUTO_TEST_CASE(convert_round_trips_through_every_writable_format) {
    const pv::test::ScratchDir dir("cli_convert");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    const auto original = pv::read_mesh(input);
    for (const char* name : {"a.vtk", "b.vtu", "c.msh", "d.mesh"}) {
        BOOST_TEST_REQUIRE(run_cli("convert " + quoted(input) + " " + quoted(dir / name)).exit_code == 0);
        const auto copy = pv::read_mesh(dir / name);
        BOOST_TEST(copy.mesh.num_elements() == original.mesh.num_elements());
        BOOST_TEST(std::equal(copy.mesh.coordinates().begin(), copy.mesh.coordinates().end(),
                              original.mesh.coordinates().begin()));
    }
}

BOOST_AUTO_TEST_CASE(perturb_makes_a_reproducible_tangle_that_improve_undoes) {
    const pv::test::ScratchDir dir("cli_perturb");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    for (const char* name : {"a.vtk", "b.vtk"})
        BOOST_TEST_REQUIRE(run_cli("perturb -q " + quoted(input) + " -o " + quoted(dir / name) +
                                   " --fraction 0.2 --amount 1 --seed 7").exit_code == 0);
    const auto a = pv::read_mesh(dir / "a.vtk"), b = pv::read_mesh(dir / "b.vtk");
    BOOST_TEST(std::equal(a.mesh.coordinates().begin(), a.mesh.coordinates().end(), b.mesh.coordinates().begin()));
    const auto tangled = nlohmann::json::parse(run_cli("quality --json " + quoted(dir / "a.vtk")).output);
    BOOST_TEST(tangled["inverted"].get<int>() > 0);
    BOOST_TEST(run_cli("improve -q " + quoted(dir / "a.vtk") + " -o " + quoted(dir / "c.vtk")).exit_code == 0);
    BOOST_TEST(nlohmann::json::parse(run_cli("quality --json " + quoted(dir / "c.vtk")).output)["inverted"].get<int>() == 0);
    const auto bad = run_cli("perturb " + quoted(input) + " -o " + quoted(dir / "d.vtk") + " --fraction 2");
    BOOST_TEST(bad.exit_code == 2);
    BOOST_TEST(has(bad.output, "fraction"));
}

// A batch of runs must tell which input failed: on meshes where nothing can move (every vertex on
// the boundary), a surface the solvers do not take and a bad flag value, the message on stderr
// names the input, and the summary carries it.
BOOST_AUTO_TEST_CASE(improve_and_run_name_the_input_in_their_errors_and_failures) {
    const pv::test::ScratchDir dir("cli_names_input");
    const std::string head = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n";
    pv::test::write_file(dir / "one_tet.vtk", head + "POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                                     "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n");
    pv::test::write_file(dir / "two_tets.vtk", head + "POINTS 7 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n-1 0 0\n0 -1 0\n"
                                                      "0 0 -1\nCELLS 2 10\n4 0 1 2 3\n4 0 4 6 5\nCELL_TYPES 2\n10\n10\n");
    pv::test::write_file(dir / "triangles.vtk", head + "POINTS 4 double\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                                                       "CELLS 2 8\n3 0 1 2\n3 0 2 3\nCELL_TYPES 2\n5\n5\n");
    // Four triangles on one edge: a non-manifold surface.
    pv::test::write_file(dir / "surface.vtk", head + "POINTS 6 double\n0 0 0\n1 0 0\n0.5 1 0\n0.5 -1 0\n0.5 0 1\n0.5 0.5 0.6\n"
                                                     "CELLS 4 16\n3 0 1 2\n3 1 0 3\n3 0 1 4\n3 0 5 1\nCELL_TYPES 4\n5\n5\n5\n5\n");
    for (const char* name : {"one_tet.vtk", "two_tets.vtk", "triangles.vtk"}) {
        const std::string input = (dir / name).string();
        const auto improve = run_cli("improve -q " + quoted(dir / name) + " -o " + quoted(dir / "out.vtk") + " --summary " +
                                     quoted(dir / "s.json"));
        const auto run = run_cli("run -q --set input.mesh=" + quoted(dir / name) + " --set output.mesh=" + quoted(dir / "out.vtk"));
        BOOST_TEST_CONTEXT(name << ": " << improve.output << run.output) {
            BOOST_TEST(improve.exit_code == 1);
            BOOST_TEST(has(improve.output, "paloverde: " + input + ": 'global' failed: every vertex is fixed"));
            BOOST_TEST(run.exit_code == 1);
            BOOST_TEST(has(run.output, "paloverde: " + input + ": 'global' failed: every vertex is fixed"));
            const auto summary = nlohmann::json::parse(read_text(dir / "s.json"));
            BOOST_TEST(summary["input"].get<std::string>() == input);
            BOOST_TEST(summary["status"].get<std::string>() == "failed");
        }
    }
    // Errors, not failures: one raised while the run reads its input, one from a flag's value.
    const std::string surface = (dir / "surface.vtk").string();
    const auto error = run_cli("improve -q " + quoted(dir / "surface.vtk") + " -o " + quoted(dir / "out.vtk"));
    BOOST_TEST(error.exit_code == 1);
    BOOST_TEST(has(error.output, "paloverde: error: " + surface + ": "), error.output);
    const std::string tet = (dir / "one_tet.vtk").string();
    const auto usage = run_cli("improve " + quoted(dir / "one_tet.vtk") + " -o " + quoted(dir / "out.vtk") + " --iterations -4");
    BOOST_TEST(usage.exit_code == 2);
    BOOST_TEST(has(usage.output, "paloverde: " + tet + ": --iterations"), usage.output);
}

// A tangled mesh and its mirror (the other orientation convention): the mirror is read flipped,
// has the same inverted count, is untangled and improved to the same coordinates, and the mesh
// written from it keeps the mirror's element order.
BOOST_AUTO_TEST_CASE(improve_treats_a_mirrored_file_as_the_original) {
    const pv::test::ScratchDir dir("cli_mirror");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    BOOST_TEST_REQUIRE(run_cli("perturb -q " + quoted(input) + " -o " + quoted(dir / "p.vtk") +
                               " --fraction 0.2 --amount 1 --seed 7").exit_code == 0);
    const auto mirror = pv::test::mirrored(pv::read_mesh(dir / "p.vtk").mesh);
    pv::write_mesh(dir / "m.vtk", mirror);
    nlohmann::json summary[2];
    const char* names[2] = {"p", "m"};
    for (int i = 0; i < 2; ++i) {
        const std::string name = names[i];
        const auto result = run_cli("improve " + quoted(dir / (name + ".vtk")) + " -o " + quoted(dir / (name + "_out.vtk")) +
                                    " --iterations 20 --threads 1 --summary " + quoted(dir / (name + ".json")));
        BOOST_TEST_INFO(result.output);
        BOOST_TEST_REQUIRE(result.exit_code == 0);
        BOOST_TEST(has(result.output, "elements flipped") == (i == 1));
        summary[i] = nlohmann::json::parse(read_text(dir / (name + ".json")));
    }
    BOOST_TEST(!summary[0]["input_orientation"]["flipped"].get<bool>());
    BOOST_TEST(summary[1]["input_orientation"]["flipped"].get<bool>());
    BOOST_TEST(summary[1]["input_orientation"]["sign"].get<int>() == -1);
    BOOST_TEST(summary[0]["inverted_before"].get<int>() > 0);
    for (const char* key : {"inverted_before", "inverted_after", "worst_after", "iterations"})
        BOOST_TEST(summary[0][key] == summary[1][key], key);
    pv::ReadOptions as_is;
    as_is.orientation = pv::OrientationMode::AsIs;
    const auto p_out = pv::read_mesh(dir / "p_out.vtk").mesh, m_out = pv::read_mesh(dir / "m_out.vtk", as_is).mesh;
    BOOST_TEST(std::equal(m_out.connectivity().begin(), m_out.connectivity().end(), mirror.connectivity().begin(),
                          mirror.connectivity().end()));
    BOOST_TEST(std::equal(m_out.coordinates().begin(), m_out.coordinates().end(), p_out.coordinates().begin(),
                          p_out.coordinates().end()));
    // Forced: as_is counts the mirror's elements as they are, flipped inverts the original's.
    const auto counted = [&](const std::string& file, const std::string& mode) {
        const auto r = run_cli("quality --json --orientation " + mode + " " + quoted(dir / file));
        BOOST_TEST_REQUIRE(r.exit_code == 0);
        return nlohmann::json::parse(r.output);
    };
    const int inverted = summary[0]["inverted_before"].get<int>();
    const int degenerate = counted("p.vtk", "auto")["degenerate"].get<int>();
    BOOST_TEST(counted("m.vtk", "auto")["inverted"].get<int>() == inverted);
    BOOST_TEST(counted("m.vtk", "as_is")["inverted"].get<int>() == mirror.num_elements() - inverted - degenerate);
    BOOST_TEST(counted("p.vtk", "flipped")["inverted"].get<int>() == mirror.num_elements() - inverted - degenerate);
    BOOST_TEST(counted("p.vtk", "flipped")["input_orientation"]["mode"] == "flipped");
    const auto config = run_cli("improve " + quoted(dir / "m.vtk") + " -o x.vtk --orientation as_is --print-config");
    BOOST_TEST(has(config.output, "orientation: as_is"));
    BOOST_TEST(run_cli("improve " + quoted(dir / "m.vtk") + " -o x.vtk --orientation sideways").exit_code == 2);
}

// --untangle stops once no element is inverted, with either solver that untangles; Laplace
// smoothing does not untangle, and says so.
BOOST_AUTO_TEST_CASE(untangle_only_works_for_global_and_local) {
    const pv::test::ScratchDir dir("cli_untangle");
    const auto input = pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk");
    for (const std::string method : {"global", "local"}) {
        const auto result = run_cli("improve -q " + quoted(input) + " -o " + quoted(dir / "out.vtk") + " --method " +
                                    method + " --untangle --summary " + quoted(dir / "s.json"));
        BOOST_TEST_INFO(method << ": " << result.output);
        BOOST_TEST_REQUIRE(result.exit_code == 0);
        const auto s = nlohmann::json::parse(read_text(dir / "s.json"));
        BOOST_TEST(s["inverted_before"].get<int>() == 9);
        BOOST_TEST(s["inverted_after"].get<int>() == 0);
        BOOST_TEST(s["iterations"] == s["untangle_iterations"]);  // no shape iterations
        BOOST_TEST(s["untangle_iterations"].get<int>() > 0);
    }
    // The same through a config: an untangle step with the local solver.
    pv::test::write_file(dir / "run.yaml", "input: {mesh: " + input.string() + "}\nqueue: [untangle: local]\n");
    const auto run = run_cli("run --json " + quoted(dir / "run.yaml"));
    BOOST_TEST_REQUIRE(run.exit_code == 0, run.output);
    BOOST_TEST(nlohmann::json::parse(run.output)["inverted_after"].get<int>() == 0);
    for (const std::string method : {"laplace", "smart_laplace"}) {
        const auto result = run_cli("improve " + quoted(input) + " -o " + quoted(dir / "out.vtk") + " --method " + method +
                                    " --untangle");
        BOOST_TEST(result.exit_code == 2);
        BOOST_TEST(has(result.output, "does not untangle"), result.output);
    }
}

// --boundary slide: the local smoother and the global solver slide the boundary and the summary
// says how far it went; Laplace smoothing keeps the boundary fixed and says so; a bad mode or
// angle is a usage error.
BOOST_AUTO_TEST_CASE(boundary_slide_with_the_local_smoother) {
    const pv::test::ScratchDir dir("cli_slide");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    const auto out = quoted(dir / "out.vtk");
    const auto result = run_cli("improve -q " + quoted(input) + " -o " + out +
                                " --method local --boundary slide --feature-angle 35 --summary " + quoted(dir / "s.json"));
    BOOST_TEST_REQUIRE(result.exit_code == 0, result.output);
    const auto s = nlohmann::json::parse(read_text(dir / "s.json"));
    const auto& motion = s["steps"][0]["summary"]["boundary"];
    BOOST_TEST(motion["moved"].get<long>() > 0);
    BOOST_TEST(motion["largest_distance"].get<double>() <= 1e-9);
    BOOST_TEST(motion["volume_before"].get<double>() > 0.0);
    const auto full = run_cli("improve " + quoted(input) + " -o " + out + " --method local --boundary slide");
    BOOST_TEST(has(full.output, "sliding vertices moved; largest distance from the input's boundary"), full.output);
    // The config the flags stand for.
    const auto config = run_cli("improve " + quoted(input) + " -o " + out + " --method local --boundary slide --print-config");
    BOOST_TEST(has(config.output, "boundary: slide"), config.output);
    // The global solver (the default method) slides too; Laplace smoothing refuses.
    for (const std::string method : {"", " --method global"}) {
        const auto global = run_cli("improve -q " + quoted(input) + " -o " + out + method +
                                    " --boundary slide --feature-angle 35 --summary " + quoted(dir / "g.json"));
        BOOST_TEST_REQUIRE(global.exit_code == 0, global.output);
        const auto g = nlohmann::json::parse(read_text(dir / "g.json"));
        BOOST_TEST(g["steps"][0]["summary"]["boundary"]["moved"].get<long>() > 0, method);
        BOOST_TEST(g["steps"][0]["summary"]["boundary"]["largest_distance"].get<double>() <= 1e-9, method);
    }
    for (const std::string flags : {"--method laplace --boundary slide", "--method smart-laplace --feature-angle 30"}) {
        const auto refused = run_cli("improve " + quoted(input) + " -o " + out + " " + flags);
        BOOST_TEST(refused.exit_code == 2, flags);
        BOOST_TEST(has(refused.output, "only some solvers slide boundary vertices (--method global or local)"), refused.output);
    }
    BOOST_TEST(run_cli("improve -q " + quoted(input) + " -o " + out + " --boundary fixed --iterations 2").exit_code == 0);
    for (const std::string flags : {"--boundary sideways", "--feature-angle 190"}) {
        const auto refused = run_cli("improve " + quoted(input) + " -o " + out + " --method local " + flags);
        BOOST_TEST(refused.exit_code == 2, flags << ": " << refused.output);
    }
}

BOOST_AUTO_TEST_SUITE_END()

// Each flag of improve is a config key: the config a command line prints, read back by `run`,
// is the same config, for every solver the registry names (and its hyphenated spelling), and
// --time-limit bounds untangling exactly for the solvers that untangle.
BOOST_AUTO_TEST_CASE(improve_flags_are_the_config_they_print) {
    const pv::test::ScratchDir dir("cli_flags_config");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    const std::string common = " -o " + quoted(dir / "out.vtu") +
                               " --iterations 7 --target 0.3 --time-limit 9 --threads 2 --fixed boundary"
                               " --orientation as_is --history h.csv --summary s.json --table t.csv --plot p.svg --ascii"
                               " --keep size,aspect --set output.metric=mean_ratio --print-config";
    const std::vector<std::pair<std::string, std::string>> methods{
        {"global", " --steepest --metric mean_ratio --barrier-shrink 0.5 --feature-angle 30 --checkpoint c.ckpt "
                   "--checkpoint-every 5 --no-untangle"},
        {"local", " --improve-below 0.5 --boundary slide --untangle"},
        {"smart-laplace", ""},
        {"laplace", " --boundary fixed"}};
    for (const auto& [method, flags] : methods) {
        BOOST_TEST_CONTEXT(method) {
            const auto printed = run_cli("improve " + quoted(input) + " --method " + method + flags + common);
            BOOST_TEST_REQUIRE(printed.exit_code == 0, printed.output);
            pv::test::write_file(dir / "run.yaml", printed.output);
            const auto again = run_cli("run " + quoted(dir / "run.yaml") + " --print-config");
            BOOST_TEST_REQUIRE(again.exit_code == 0, again.output);
            BOOST_TEST(again.output == printed.output);
            std::string name = method;
            std::replace(name.begin(), name.end(), '-', '_');
            BOOST_TEST(has(printed.output, "name: " + name), printed.output);
            BOOST_TEST(has(printed.output, "max_iterations: 7"), printed.output);
            BOOST_TEST(has(printed.output, "target_worst_quality: 0.3"), printed.output);
            // termination.max_seconds, and untangle_termination's where the solver untangles.
            const bool untangles = name == "global" || name == "local";
            std::size_t limits = 0;
            for (std::size_t at = printed.output.find("max_seconds: 9"); at != std::string::npos;
                 at = printed.output.find("max_seconds: 9", at + 1))
                ++limits;
            BOOST_TEST(limits == (untangles ? 2u : 1u), printed.output);
        }
    }
}
