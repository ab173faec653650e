#pragma once
#include <cstreams/geometry/mesh.hpp>

namespace cstreams::scenes {

// A rectangular sheet of nx by ny quads in the z = 0 plane, each split into two
// triangles along alternating diagonals; (2 nx ny) faces, corners at (0,0) and (w,h).
Mesh sheet(int nx, int ny, double width, double height);

// A sphere from a subdivided icosahedron: 20 * 4^level faces, radius r, centre c.
Mesh icosphere(int level, double radius, const Vec3& centre = Vec3::Zero());

// Appends b to a, renumbering b's vertices.
void append(Mesh& a, const Mesh& b);

}  // namespace cstreams::scenes
