#include "inputs.hpp"

#include <cstreams/io/mesh_io.hpp>
#include <cstreams/io/query_io.hpp>
#include <cstreams/scene/scene.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cstreams::fuzz {

namespace {

void expect(bool invariant, const char* what)
{
  if (!invariant) throw std::logic_error(what);
}

void check_mesh(const Mesh& m)
{
  for (const auto& f : m.faces)
    for (auto v : f) expect(v < m.positions.size(), "face index past the vertices");
  for (const auto& p : m.positions) expect(p.allFinite(), "non-finite coordinate accepted");
}

}  // namespace

void mesh_readers(std::string_view bytes)
{
  // Either reader on every input: OBJ text is a malformed PLY and the reverse.
  for (bool ply : {true, false}) {
    try {
      check_mesh(ply ? parse_ply(bytes, "fuzz.ply") : parse_obj(bytes, "fuzz.obj"));
    } catch (const InputError&) {
    }
  }
}

void scene_manifest(std::string_view bytes, const std::string& folder)
{
  try {
    const Scene scene = parse_scene_manifest(std::string(bytes), folder + "/fuzz.json");
    expect(!scene.objects.empty(), "a scene without objects");
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      for (std::size_t f = 0; f < scene.frame_count() && f < 4; ++f) {
        const auto x = scene.positions(o, f);
        expect(x.size() == scene.objects[o].topology.vertex_count, "frame vertex count differs from the topology");
      }
      for (std::uint32_t p = 0; p < scene.objects.size(); ++p)
        expect(scene.may_collide(o, p) == scene.may_collide(p, o), "collision mask not symmetric");
    }
  } catch (const InputError&) {
  }
}

void query_csv(std::string_view bytes)
{
  try {
    std::istringstream in{std::string(bytes)};
    for (const auto& q : parse_queries(in, "fuzz.csv"))
      for (const auto& p : q.points) expect(p.allFinite(), "non-finite query point accepted");
  } catch (const InputError&) {
  }
}

}  // namespace cstreams::fuzz
