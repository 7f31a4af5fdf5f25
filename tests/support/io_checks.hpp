#pragma once
// Helpers shared by the mesh-format tests (tests/io): building bad inputs, expecting read errors,
// comparing meshes and values bit for bit.
#include <filesystem>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/mesh/mesh.hpp"
#include "support/test_support.hpp"

namespace paloverde::test {

// ":N:", how a FileError names line N.
std::string line_tag(std::size_t line);

// The line tag of the end of `text` (where reading a truncated file stops).
std::string last_line(const std::string& text);

// The line tag of the first occurrence of `needle` in `text`; requires that `needle` occurs.
std::string line_of(const std::string& text, std::string_view needle);

// `text` with the first occurrence of `from` replaced by `to`; requires that `from` occurs.
std::string replaced(std::string text, std::string_view from, std::string_view to);

// The whole file, byte for byte.
std::string read_text(const std::filesystem::path& path);

// Reading `path` must throw a FileError whose message holds `named` (how the message must name
// the file at fault) and every fragment.
void check_read_error(const std::filesystem::path& path, std::string_view named,
                      std::initializer_list<std::string_view> fragments);

// Reading `path` must throw a FileError whose message names `path` in full and holds every fragment.
void check_error(const std::filesystem::path& path, std::initializer_list<std::string_view> fragments);

// Writes `text` to dir/name; reading it must throw a FileError whose message names `name` and
// holds every fragment.
void check_error_text(const ScratchDir& dir, const std::string& name, const std::string& text,
                      std::initializer_list<std::string_view> fragments);

// Writes `text` to a new file "bad<N><extension>" in `dir`; reading it must throw a FileError
// whose message names that file's full path and holds every fragment.
void check_error_in_new_file(const ScratchDir& dir, std::string_view extension, const std::string& text,
                             std::initializer_list<std::string_view> fragments);

// Six times the signed volume of tetrahedron `e` (positive when its corners are ordered the
// right-handed way).
double signed_volume(const Mesh& mesh, ElementId e);

// How many tetrahedra have a positive (or, with positive = false, a negative) signed volume.
int count_tets(const Mesh& mesh, bool positive);
inline int positive_tets(const Mesh& mesh) { return count_tets(mesh, true); }

// Same size and the same values bit for bit (so -0.0 and 0.0 differ, and NaNs compare by payload).
bool same_bits(std::span<const double> a, std::span<const double> b);

// Checks that the value arrays have the same size and the same bits.
void check_same_values(const std::vector<double>& a, const std::vector<double>& b);

// Checks the same kind, connectivity, and coordinates bit for bit (so -0.0 and 0.0 differ).
void check_same_mesh(const Mesh& a, const Mesh& b);

// A small triangle mesh off the xy plane with awkward coordinates: thirds, square roots, -0.0
// and a denormal.
Mesh awkward_triangles();

}  // namespace paloverde::test
