#pragma once
#include <cstreams/errors.hpp>
#include <cstreams/geometry/mesh.hpp>
#include <cstreams/geometry/topology.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cstreams {

class Scene;
Scene load_scene(const std::string& path);
Scene parse_scene_manifest(const std::string& text, const std::string& path);
Scene scene_from_frames(const std::vector<std::string>& frame_files, bool split);

enum class ObjectKind {
  deformable,  // every vertex moves freely
  rigid,       // moves, shape fixed
  static_      // never moves: one frame serves every step
};
const char* to_string(ObjectKind kind) noexcept;
ObjectKind parse_object_kind(const std::string& text);

// Whether objects a and b (a == b: self-collision) need collision detection: only a
// deformable object with self-collision collides with itself, two static objects
// never collide, and a pair in `ignored` (a < b) is masked off.
bool objects_may_collide(std::uint32_t a, std::uint32_t b, ObjectKind kind_a, bool self_collision_a, ObjectKind kind_b,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& ignored);

// The files of an object's frames: a list, or a pattern of one integer field (as in
// printf, "frame_%04d.ply") over a range of numbers, each name made when asked for, so
// that a manifest of a million frames (or of a pattern a thousand characters wide)
// holds no million names.
class FrameFiles {
public:
  FrameFiles() = default;
  FrameFiles(std::vector<std::string> files) : files_(std::move(files)) {}
  // Names `base` joined to `pattern` formatted with first, first + 1, ..., first + count - 1.
  FrameFiles(std::string base, std::string pattern, long first, std::size_t count)
      : base_(std::move(base)), pattern_(std::move(pattern)), first_(first), count_(count)
  {
  }

  std::size_t size() const { return pattern_.empty() ? files_.size() : count_; }
  bool empty() const { return size() == 0; }
  std::string operator[](std::size_t i) const;
  std::string front() const { return (*this)[0]; }

private:
  std::vector<std::string> files_;
  std::string base_, pattern_;
  long first_ = 0;
  std::size_t count_ = 0;
};

// One object of a scene: a triangle mesh, how it moves, and where its frames are.
struct SceneObject {
  std::string name;
  ObjectKind kind = ObjectKind::deformable;
  bool self_collision = true;
  Topology topology;
  // Frame files (one for a static object). When several objects share files (the
  // components of one mesh), `vertices` maps this object's vertex i to vertex
  // vertices[i] of the file; empty means the identity.
  FrameFiles frame_files;
  std::vector<std::uint32_t> vertices;
};

// A set of objects moving over frames, with the pairs that may collide.
//
// Frames are read when asked for, each checked against the first: same vertex count,
// same faces, finite coordinates; a mismatch is an InputError naming the file.
class Scene {
public:
  Scene();
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;

  std::string name;
  std::vector<SceneObject> objects;
  // Object pairs (a < b) masked off: they never collide with each other.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ignored_pairs;

  std::size_t frame_count() const;
  // Whether objects a and b (a may equal b: self-collision) need collision detection.
  bool may_collide(std::uint32_t a, std::uint32_t b) const;
  std::vector<Vec3> positions(std::uint32_t object, std::size_t frame) const;
  // Mesh files parsed for positions so far: a step reads each of its frames once,
  // for all the objects they hold.
  std::size_t files_read() const;
  std::uint32_t object_index(const std::string& object_name) const;
  std::size_t face_count() const;
  std::size_t vertex_count() const;

  struct Cache;  // frames read so far; opaque

private:
  friend Scene parse_scene_manifest(const std::string& text, const std::string& path);
  friend Scene scene_from_frames(const std::vector<std::string>& frame_files, bool split);
  std::unique_ptr<Cache> cache_;
};

// Reads a scene: a JSON manifest (.json, format in README.md) or one mesh file (.ply
// or .obj, a single static frame).
Scene load_scene(const std::string& path);

// A manifest's text, as if read from `path` (which names it in errors and is where its
// relative frame paths start).
Scene parse_scene_manifest(const std::string& text, const std::string& path);

// A sequence of frames of one mesh, as the UNC benchmarks come: one deformable object
// with self-collision, or with `split` one object per connected component, all
// colliding with each other and themselves.
Scene scene_from_frames(const std::vector<std::string>& frame_files, bool split = false);

}  // namespace cstreams
