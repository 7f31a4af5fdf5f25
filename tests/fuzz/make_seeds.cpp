// Builds the generated part of the seed corpus: every shared mesh under 200 KB (../shared/data),
// as found and re-written by Paloverde's writers in each format and encoding they have.
//   make_seeds SHARED_DATA_DIR OUTPUT_DIR
// writes OUTPUT_DIR/<format>/<name>.<variant>; fuzz inputs for TetGen are the .node text, the
// separator line and the .ele text in one file (see fuzz_input.hpp).
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_input.hpp"
#include "paloverde/io/mesh_io.hpp"

namespace fs = std::filesystem;
using namespace paloverde;

namespace {

constexpr std::uintmax_t kMaxSeedBytes = 200 * 1024;

std::string read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string number(double value) {
    char digits[32];
    return std::string(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
}

// TetGen has no writer: the seed is written here, numbered from 1, one point attribute.
std::string tetgen_text(const Mesh& mesh) {
    std::ostringstream out;
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    out << "# generated from a shared mesh\n" << n << " 3 1 0\n";
    for (std::size_t v = 0; v < n; ++v) {
        out << v + 1;
        for (int c = 0; c < 3; ++c) out << ' ' << number(mesh.coordinates()[3 * v + c]);
        out << ' ' << v % 5 << '\n';
    }
    out << fuzz::kTetgenSeparator.substr(1);
    const int k = mesh.corners();
    out << mesh.num_elements() << ' ' << k << " 0\n";
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        out << e + 1;
        for (VertexId v : mesh.element(e)) out << ' ' << v + 1;
        out << '\n';
    }
    return out.str();
}

void write_seed(const fs::path& dir, const std::string& name, const std::string& bytes) {
    fs::create_directories(dir);
    fuzz::write_bytes(dir / name, bytes);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::cerr << "usage: make_seeds SHARED_DATA_DIR OUTPUT_DIR\n";
        return 2;
    }
    const fs::path shared = argv[1];
    const fs::path out = argv[2];
    std::vector<fs::path> meshes;
    for (const auto& entry : fs::recursive_directory_iterator(shared)) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".vtk" || ext == ".node" || ext == ".mesh") &&
            entry.file_size() <= kMaxSeedBytes)
            meshes.push_back(entry.path());
    }
    std::sort(meshes.begin(), meshes.end());
    if (meshes.empty()) {
        std::cerr << "make_seeds: no mesh under 200 KB in " << shared << "\n";
        return 1;
    }
    const fs::path scratch = out / "scratch";
    fs::create_directories(scratch);
    int written = 0;
    for (const fs::path& path : meshes) {
        const std::string name = path.stem().string();
        // The file as it is, in its own format.
        if (path.extension() == ".node") {
            fs::path ele = path;
            ele.replace_extension(".ele");
            std::string both = read_bytes(path);
            both += fuzz::kTetgenSeparator;
            both += read_bytes(ele);
            if (both.size() <= kMaxSeedBytes) write_seed(out / "tetgen", name + ".tetgen", both);
        } else {
            write_seed(out / (path.extension() == ".vtk" ? "vtk" : "medit"), path.filename().string(), read_bytes(path));
        }
        // Every format and encoding the writers have, with the file's fields. (A file Paloverde
        // refuses is a seed as it is, but has nothing to re-write.)
        MeshFile file;
        try {
            file = read_mesh(path);
        } catch (const Error&) {
            continue;
        }
        struct Variant {
            const char* dir;
            const char* extension;
            MeshFormat format;
            Encoding encoding;
        };
        const Variant variants[] = {
            {"vtk", ".ascii.vtk", MeshFormat::VtkLegacy, Encoding::Ascii},
            {"vtk", ".binary.vtk", MeshFormat::VtkLegacy, Encoding::Binary},
            {"vtu", ".ascii.vtu", MeshFormat::Vtu, Encoding::Ascii},
            {"vtu", ".appended.vtu", MeshFormat::Vtu, Encoding::Binary},
            {"gmsh", ".ascii.msh", MeshFormat::Gmsh, Encoding::Ascii},
            {"gmsh", ".binary.msh", MeshFormat::Gmsh, Encoding::Binary},
            {"medit", ".written.mesh", MeshFormat::Medit, Encoding::Ascii},
        };
        for (const Variant& v : variants) {
            WriteOptions options;
            options.format = v.format;
            options.encoding = v.encoding;
            const fs::path target = scratch / ("seed" + std::string(v.extension));
            try {
                write_mesh(target, file.mesh, options, file.point_fields, file.cell_fields);
            } catch (const Error&) {
                write_mesh(target, file.mesh, options);  // fields this format cannot hold
            }
            const std::string bytes = read_bytes(target);
            if (bytes.size() <= kMaxSeedBytes) {
                write_seed(out / v.dir, name + v.extension, bytes);
                ++written;
            }
        }
        if (file.mesh.has_cells()) continue;  // TetGen holds triangles or tetrahedra only
        const std::string tetgen = tetgen_text(file.mesh);
        if (tetgen.size() <= kMaxSeedBytes) write_seed(out / "tetgen", name + ".written.tetgen", tetgen);
    }
    fs::remove_all(scratch);
    std::cout << "make_seeds: " << meshes.size() << " shared meshes, " << written << " re-written seeds in " << out
              << "\n";
    return 0;
}
