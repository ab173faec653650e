#include <cstreams/io/mesh_io.hpp>
#include <cstreams/scene/scene.hpp>

#include "../support/scratch.hpp"

#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace cstreams;

namespace {

Mesh tetrahedron()
{
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1.25)};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}

template <class T> void put(std::string& out, T value, bool big)
{
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

// A PLY of the tetrahedron with an extra vertex property and an extra element, in the
// given encoding and coordinate type, the way real files vary.
template <class Coord> std::string ply_bytes(const Mesh& m, const char* format, const char* type)
{
  std::string out = std::string("ply\nformat ") + format + " 1.0\ncomment made by a test\n" +
                    "element vertex " + std::to_string(m.positions.size()) + "\nproperty " + type + " x\nproperty " +
                    type + " y\nproperty " + type + " z\nproperty uchar red\n" +
                    "element face " + std::to_string(m.faces.size()) + "\nproperty list uint8 int32 vertex_indices\n" +
                    "element material 1\nproperty float shine\nend_header\n";
  const bool ascii = std::string(format) == "ascii", big = std::string(format) == "binary_big_endian";
  for (const auto& p : m.positions) {
    if (ascii) {
      out += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + " 7\n";
    } else {
      for (int k = 0; k < 3; ++k) put<Coord>(out, Coord(p[k]), big);
      put<std::uint8_t>(out, 7, big);
    }
  }
  for (const auto& f : m.faces) {
    if (ascii) {
      out += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
    } else {
      put<std::uint8_t>(out, 3, big);
      for (auto i : f) put<std::int32_t>(out, std::int32_t(i), big);
    }
  }
  if (ascii) out += "0.5\n";
  else put<float>(out, 0.5f, big);
  return out;
}

std::string temp_dir(const std::string& name) { return cstreams::test::fresh_scratch("mesh-io-" + name).string(); }

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

}  // namespace

TEST_CASE("PLY in every encoding and coordinate type reads the same mesh", "[host][io][quick]")
{
  const Mesh m = tetrahedron();
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    INFO(format);
    const Mesh f = parse_ply(ply_bytes<float>(m, format, "float"), "t.ply");
    const Mesh d = parse_ply(ply_bytes<double>(m, format, "double"), "t.ply");
    CHECK(f.faces == m.faces);
    CHECK(d.faces == m.faces);
    CHECK(f.positions == m.positions);
    CHECK(d.positions == m.positions);
  }
}

TEST_CASE("malformed PLY files are errors naming the file and the element", "[host][io][quick]")
{
  const Mesh m = tetrahedron();
  const std::string good = ply_bytes<float>(m, "binary_little_endian", "float");
  const auto fails_with = [](const std::string& bytes, const std::string& text) {
    try {
      parse_ply(bytes, "bad.ply");
      FAIL("a malformed PLY was accepted");
    } catch (const InputError& e) {
      CHECK_THAT(std::string(e.what()), Catch::Contains("bad.ply") && Catch::Contains(text));
    }
  };
  SECTION("truncated inside the faces")
  {
    // The last 20 bytes are the material (4) and face 3 (13) and the end of face 2.
    fails_with(good.substr(0, good.size() - 20), "face 2");
    fails_with(good.substr(0, good.size() - 20), "truncated");
  }
  SECTION("header problems name the line") { fails_with("ply\nformat ascii 1.0\nelement vertex x\n", "bad.ply:3"); }
  SECTION("not a PLY file") { fails_with("solid cube\n", "not a PLY file"); }
  SECTION("no end_header") { fails_with("ply\nformat ascii 1.0\nelement vertex 0\n", "without end_header"); }
  SECTION("counts larger than the file") { fails_with("ply\nformat binary_little_endian 1.0\nelement vertex 999999999\nproperty float x\nproperty float y\nproperty float z\nend_header\n", "more than the file can hold"); }
  SECTION("a vertex index out of range")
  {
    Mesh bad = m;
    bad.faces[2][1] = 9;
    fails_with(ply_bytes<float>(bad, "ascii", "float"), "face 2 refers to vertex 9");
  }
  SECTION("a face that repeats a vertex")
  {
    Mesh bad = m;
    bad.faces[1] = {3, 1, 3};
    fails_with(ply_bytes<float>(bad, "ascii", "float"), "face 1 repeats vertex 3");
  }
  SECTION("NaN and infinite coordinates")
  {
    Mesh bad = m;
    bad.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
    fails_with(ply_bytes<double>(bad, "binary_big_endian", "double"), "vertex 2 has a NaN or infinite coordinate");
    bad.positions[2].y() = std::numeric_limits<double>::infinity();
    fails_with(ply_bytes<double>(bad, "binary_little_endian", "double"), "vertex 2");
  }
  SECTION("a quad")
  {
    std::string text = ply_bytes<float>(m, "ascii", "float");
    text.replace(text.find("3 1 2 3"), 7, "4 1 2 3 0");
    fails_with(text, "face 2 has 4 vertices");
  }
  SECTION("unreadable ascii numbers name the line") { fails_with("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 x3\n", "bad.ply:8"); }
}

TEST_CASE("OBJ reads triangles in every index form and names lines in errors", "[host][io][quick]")
{
  const Mesh m = parse_obj("# tetra\nv 0 0 0\nv 1 0 0\nvt 0 0\nvn 0 0 1\nv 0 1 0\nv 0 0 1.25\n"
                           "o t\nf 1 3 2\nf 1/1 2/1 4/1\nf 2//1 3//1 4//1\nf -4/1/1 -1/1/1 -2/1/1\n",
                           "t.obj");
  CHECK(m.faces == tetrahedron().faces);
  CHECK(m.positions == tetrahedron().positions);
  CHECK_THROWS_WITH(parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 1\n", "q.obj"),
                    Catch::Contains("q.obj:4") && Catch::Contains("only triangles"));
  CHECK_THROWS_WITH(parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 7\n", "q.obj"),
                    Catch::Contains("q.obj:5: face refers to vertex 6"));
  CHECK_THROWS_WITH(parse_obj("v 0 nan 0\n", "q.obj"), Catch::Contains("q.obj:1: vertex has a NaN"));
  CHECK_THROWS_WITH(parse_obj("v 0 0\n", "q.obj"), Catch::Contains("q.obj:1"));
  CHECK_THROWS_WITH(parse_obj("v 0 0 0\nf a b c\n", "q.obj"), Catch::Contains("q.obj:2"));
}

TEST_CASE("write_ply round-trips exactly and leaves nothing behind on failure", "[host][io][quick]")
{
  const std::string dir = temp_dir("write-ply");
  Mesh m = tetrahedron();
  m.positions[1].x() = 0.1;  // not a float: a double PLY must keep it exactly
  for (auto encoding : {PlyEncoding::ascii, PlyEncoding::binary_little_endian}) {
    write_ply(dir + "/t.ply", m, encoding);
    const Mesh back = read_ply(dir + "/t.ply");
    CHECK(back.positions == m.positions);
    CHECK(back.faces == m.faces);
  }
  CHECK_THROWS_AS(write_ply(dir + "/missing/t.ply", m), InputError);
  CHECK(access((dir + "/missing/t.ply.partial").c_str(), F_OK) != 0);
}

TEST_CASE("scenes check every frame against the first", "[host][scene][quick]")
{
  const std::string dir = temp_dir("scene-frames");
  Mesh m = tetrahedron();
  write_ply(dir + "/0.ply", m);
  m.positions[0].z() = -0.5;
  write_ply(dir + "/1.ply", m);
  Mesh fewer = m;
  fewer.positions.pop_back();
  fewer.faces = {{0, 2, 1}};
  write_ply(dir + "/2.ply", fewer);
  Mesh other = m;
  std::swap(other.faces[0], other.faces[1]);
  write_ply(dir + "/3.ply", other);

  const Scene ok = scene_from_frames({dir + "/0.ply", dir + "/1.ply"});
  CHECK(ok.frame_count() == 2);
  CHECK(ok.positions(0, 1)[0].z() == -0.5);
  const Scene s = scene_from_frames({dir + "/0.ply", dir + "/2.ply", dir + "/3.ply"});
  CHECK_THROWS_WITH(s.positions(0, 1), Catch::Contains("2.ply") && Catch::Contains("has 3 vertices but the first frame"));
  CHECK_THROWS_WITH(s.positions(0, 2), Catch::Contains("3.ply: faces differ from the first frame") && Catch::Contains("face 0"));
  CHECK_THROWS_WITH(s.positions(0, 3), Catch::Contains("frame 3 does not exist"));
}

TEST_CASE("manifests describe objects, kinds, frames and masks", "[host][scene][quick]")
{
  const std::string dir = temp_dir("manifest");
  Mesh a = tetrahedron(), b = tetrahedron();
  for (auto& p : b.positions) p.x() += 3;
  Mesh two;  // two tetrahedra in one file: split into components
  two.positions = a.positions;
  two.positions.insert(two.positions.end(), b.positions.begin(), b.positions.end());
  two.faces = a.faces;
  for (auto f : b.faces) two.faces.push_back({f[0] + 4, f[1] + 4, f[2] + 4});
  for (int i = 0; i < 3; ++i) write_ply(dir + "/cloth_" + std::to_string(i) + ".ply", two);
  write_ply(dir + "/floor.ply", a);
  write_text(dir + "/scene.json", R"({
    "name": "test",
    "objects": [
      {"name": "pair", "frames": {"pattern": "cloth_%d.ply", "first": 0, "count": 3}, "split_components": true},
      {"name": "floor", "kind": "static", "frames": "floor.ply"}
    ],
    "ignore_pairs": [["pair#1", "floor"]]
  })");
  const Scene s = load_scene(dir + "/scene.json");
  REQUIRE(s.objects.size() == 3);
  CHECK(s.objects[0].name == "pair#0");
  CHECK(s.objects[1].topology.faces.size() == 4);
  CHECK(s.objects[1].vertices == std::vector<std::uint32_t>{4, 5, 6, 7});
  CHECK(s.positions(1, 2)[0].x() == 3);
  CHECK(s.objects[2].kind == ObjectKind::static_);
  CHECK(s.frame_count() == 3);
  CHECK(s.positions(2, 2) == a.positions);  // a static object has one frame for all
  CHECK(s.may_collide(0, 0));
  CHECK(s.may_collide(0, 2));
  CHECK_FALSE(s.may_collide(1, 2));
  CHECK_FALSE(s.may_collide(2, 2));

  write_text(dir + "/bad.json", R"({"objects": [{"name": "x", "kind": "squishy", "frames": "floor.ply"}]})");
  CHECK_THROWS_WITH(load_scene(dir + "/bad.json"), Catch::Contains("squishy"));
  write_text(dir + "/bad2.json", R"({"objects": [{"name": "x", "frames": {"pattern": "%s.ply", "count": 2}}]})");
  CHECK_THROWS_WITH(load_scene(dir + "/bad2.json"), Catch::Contains("bad2.json: object x") && Catch::Contains("pattern"));
  write_text(dir + "/bad3.json", "{\"objects\": [");
  CHECK_THROWS_WITH(load_scene(dir + "/bad3.json"), Catch::Contains("bad3.json: not valid JSON"));
  write_text(dir + "/bad4.json", R"({"objects": [{"name": "x", "frames": ["missing.ply"]}]})");
  CHECK_THROWS_WITH(load_scene(dir + "/bad4.json"), Catch::Contains("missing.ply: no such mesh file"));
}

// A pattern names its frames as they are read: a manifest of a million frames, each
// name hundreds of characters wide, had held hundreds of megabytes of names (a fuzzed
// manifest of 911 bytes ran the parser out of memory).
TEST_CASE("a manifest's frame pattern names each frame as it is read, a million of them at no cost", "[host][scene][quick]")
{
  const std::string dir = temp_dir("frame-pattern");
  write_ply(dir + "/cloth_0.ply", tetrahedron());
  write_ply(dir + "/cloth_" + std::string(199, '0') + "7.ply", tetrahedron());
  write_text(dir + "/wide.json", R"({"objects": [
    {"name": "a", "frames": {"pattern": "cloth_%d.ply", "first": 0, "count": 1000000}},
    {"name": "b", "frames": {"pattern": "cloth_%0200d.ply", "first": 7, "count": 1000000}}
  ]})");
  const Scene s = load_scene(dir + "/wide.json");
  REQUIRE(s.objects.size() == 2);
  CHECK(s.frame_count() == 1000000);
  CHECK(s.objects[0].frame_files[999999] == dir + "/cloth_999999.ply");
  CHECK(s.objects[1].frame_files[999993] == dir + "/cloth_" + std::string(193, '0') + "1000000.ply");
  CHECK(s.positions(0, 0) == tetrahedron().positions);
  CHECK_THROWS_WITH(s.positions(0, 1), Catch::Contains("cloth_1.ply"));
  // A field wider than a path can be is refused as the manifest is read: printf cannot
  // make such a name (a fuzzed field 100 digits wide ended the parser).
  write_text(dir + "/wider.json", R"({"objects": [{"name": "a", "frames": {"pattern": "cloth_%04096d.ply", "count": 2}}]})");
  CHECK_THROWS_WITH(load_scene(dir + "/wider.json"),
                    Catch::Contains("wider.json: object a") && Catch::Contains("4096 characters wide; at most 4095"));
}
