#pragma once
#include <cstreams/errors.hpp>
#include <cstreams/geometry/mesh.hpp>

#include <string>
#include <string_view>

namespace cstreams {

// Reads a triangle mesh from PLY (ascii, binary little- or big-endian; any numeric
// vertex type; extra elements and properties ignored) or OBJ (v and f lines; f as
// i, i/t, i//n or i/t/n, negative indices relative). The format comes from the
// extension. Throws InputError naming the file and the line, element or byte at fault
// for a malformed or truncated file, a non-triangle face, an index out of range, a face
// that repeats a vertex, or a NaN or infinite coordinate.
Mesh read_mesh(const std::string& path);
Mesh read_ply(const std::string& path);
Mesh read_obj(const std::string& path);

// The same readers over bytes in memory; `name` stands for the file in messages.
Mesh parse_ply(std::string_view bytes, const std::string& name);
Mesh parse_obj(std::string_view bytes, const std::string& name);

enum class PlyEncoding { ascii, binary_little_endian };
// Writes through a temporary file renamed into place, so a failure leaves no partial file.
void write_ply(const std::string& path, const Mesh& mesh, PlyEncoding encoding = PlyEncoding::binary_little_endian);

}  // namespace cstreams
