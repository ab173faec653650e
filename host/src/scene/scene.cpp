#include <cstreams/io/file_input.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/scene/scene.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace cstreams {

const char* to_string(ObjectKind kind) noexcept
{
  switch (kind) {
    case ObjectKind::deformable: return "deformable";
    case ObjectKind::rigid: return "rigid";
    case ObjectKind::static_: return "static";
  }
  return "?";
}

ObjectKind parse_object_kind(const std::string& text)
{
  for (auto k : {ObjectKind::deformable, ObjectKind::rigid, ObjectKind::static_})
    if (text == to_string(k)) return k;
  throw InputError("unknown object kind '" + text + "' (deformable, rigid or static)");
}

// The last frame file read, the first frame it was last found to match, and the faces
// and vertex count of each object's first frame, against which every later frame is
// checked. The objects of a mesh split into its components share both files: the
// frame is read and checked once for all of them.
struct Scene::Cache {
  std::string path, matched_first;
  Mesh mesh;
  std::map<std::string, Mesh> first_frames;
  std::size_t reads = 0;

  const Mesh& load(const std::string& file)
  {
    if (file != path) {
      path.clear();
      matched_first.clear();
      mesh = read_mesh(file);
      path = file;
      ++reads;
    }
    return mesh;
  }
};

Scene::Scene() : cache_(std::make_unique<Cache>()) {}
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

std::size_t Scene::frame_count() const
{
  std::size_t count = 1;
  for (const auto& o : objects)
    if (o.kind != ObjectKind::static_) count = std::max(count, o.frame_files.size());
  return count;
}

bool objects_may_collide(std::uint32_t a, std::uint32_t b, ObjectKind kind_a, bool self_collision_a, ObjectKind kind_b,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& ignored)
{
  if (a == b) return self_collision_a && kind_a == ObjectKind::deformable;
  if (kind_a == ObjectKind::static_ && kind_b == ObjectKind::static_) return false;
  const auto key = std::make_pair(std::min(a, b), std::max(a, b));
  return std::find(ignored.begin(), ignored.end(), key) == ignored.end();
}

bool Scene::may_collide(std::uint32_t a, std::uint32_t b) const
{
  return objects_may_collide(a, b, objects[a].kind, objects[a].self_collision, objects[b].kind, ignored_pairs);
}

std::uint32_t Scene::object_index(const std::string& object_name) const
{
  for (std::uint32_t i = 0; i < objects.size(); ++i)
    if (objects[i].name == object_name) return i;
  throw InputError("scene " + name + " has no object named '" + object_name + "'");
}

std::size_t Scene::face_count() const
{
  std::size_t n = 0;
  for (const auto& o : objects) n += o.topology.faces.size();
  return n;
}

std::size_t Scene::vertex_count() const
{
  std::size_t n = 0;
  for (const auto& o : objects) n += o.topology.vertex_count;
  return n;
}

namespace {

void check_frame(const std::string& file, const Mesh& mesh, const std::string& first_file, const Mesh& first)
{
  if (mesh.positions.size() != first.positions.size())
    throw InputError(file + ": has " + std::to_string(mesh.positions.size()) + " vertices but the first frame " +
                     first_file + " has " + std::to_string(first.positions.size()));
  if (mesh.faces != first.faces) {
    std::size_t f = 0;
    while (f < std::min(mesh.faces.size(), first.faces.size()) && mesh.faces[f] == first.faces[f]) ++f;
    throw InputError(file + ": faces differ from the first frame " + first_file + " (from face " + std::to_string(f) +
                     ")");
  }
}

}  // namespace

std::size_t Scene::files_read() const { return cache_->reads; }

std::vector<Vec3> Scene::positions(std::uint32_t object, std::size_t frame) const
{
  if (object >= objects.size()) throw InputError("scene " + name + " has no object " + std::to_string(object));
  const SceneObject& o = objects[object];
  if (frame >= frame_count())
    throw InputError("scene " + name + " has " + std::to_string(frame_count()) + " frames; frame " +
                     std::to_string(frame) + " does not exist");
  const std::string file = o.frame_files[std::min(frame, o.frame_files.size() - 1)];
  const Mesh& first = cache_->first_frames.at(o.frame_files.front());
  const Mesh& mesh = cache_->load(file);
  if (cache_->matched_first != o.frame_files.front()) check_frame(file, mesh, o.frame_files.front(), first);
  cache_->matched_first = o.frame_files.front();
  if (o.vertices.empty()) return mesh.positions;
  std::vector<Vec3> out(o.vertices.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = mesh.positions[o.vertices[i]];
  return out;
}

namespace {

std::string folder_of(const std::string& path)
{
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string resolve(const std::string& base, const std::string& file)
{
  return !file.empty() && file[0] == '/' ? file : base + file;
}

// Adds one object per mesh (or per component) of a frame sequence.
void add_objects(Scene& scene, Scene::Cache& cache, SceneObject prototype, bool split)
{
  const Mesh& first = cache.first_frames.emplace(prototype.frame_files.front(), read_mesh(prototype.frame_files.front()))
                          .first->second;
  if (first.faces.empty()) throw InputError(prototype.frame_files.front() + ": the mesh has no faces");
  if (!split) {
    prototype.topology = build_topology(first.faces, first.positions.size());
    scene.objects.push_back(std::move(prototype));
    return;
  }
  const auto components = connected_components(first.faces, first.positions.size());
  for (std::size_t c = 0; c < components.size(); ++c) {
    SceneObject o = prototype;
    o.name = prototype.name + "#" + std::to_string(c);
    o.topology = build_topology(components[c].faces, components[c].vertices.size());
    o.vertices = components[c].vertices;
    scene.objects.push_back(std::move(o));
  }
}

// A whole-number field of a JSON object (`fallback` when absent), within [lo, hi]. Read
// as JSON rather than converted, since converting 4.4e19 to a long is undefined.
long whole_number(const nlohmann::json& object, const char* key, long fallback, long lo, long hi,
                  const std::string& where)
{
  const auto it = object.find(key);
  long value = fallback;
  bool whole = true;
  if (it != object.end()) {
    // Signed integers are held as int64 (a long here); only unsigned ones may not fit.
    whole = it->is_number_integer() && !(it->is_number_unsigned() && it->get<std::uint64_t>() > std::uint64_t(hi));
    if (whole) value = it->get<long>();
  }
  if (!whole || value < lo || value > hi)
    throw InputError(where + ": \"" + key + "\" must be a whole number from " + std::to_string(lo) + " to " +
                     std::to_string(hi));
  return value;
}

FrameFiles frame_list(const nlohmann::json& frames, const std::string& base, const std::string& where)
{
  std::vector<std::string> files;
  if (frames.is_string()) {
    files.push_back(resolve(base, frames.get<std::string>()));
  } else if (frames.is_array()) {
    for (const auto& f : frames) {
      if (!f.is_string()) throw InputError(where + ": every entry of \"frames\" must be a file name");
      files.push_back(resolve(base, f.get<std::string>()));
    }
  } else if (frames.is_object()) {
    const std::string pattern = frames.value("pattern", "");
    static const std::regex one_integer(R"(^[^%]*%0?([0-9]*)d[^%]*$)");
    std::smatch field;
    if (!std::regex_match(pattern, field, one_integer))
      throw InputError(where + ": \"pattern\" must hold exactly one integer field such as %d or %03d");
    // A name is made as its frame is read (FrameFiles): a field wider than a path can be
    // is refused here, where printf would fail or make gigabytes of padding.
    std::string width = field[1].str();
    width.erase(0, std::min(width.find_first_not_of('0'), width.size()));
    if (width.size() > 4 || (!width.empty() && std::stoi(width) > 4095))
      throw InputError(where + ": the integer field of \"pattern\" is " + width + " characters wide; at most 4095");
    // Bounded so that first + count - 1 stays an int, and a typo cannot ask for 10^15 files.
    const long first = whole_number(frames, "first", 0, 0, 1000000000, where);
    const long count = whole_number(frames, "count", -1, 1, 1000000, where);
    return FrameFiles(base, pattern, first, std::size_t(count));
  } else {
    throw InputError(where + ": \"frames\" must be a file, a list of files or a pattern");
  }
  if (files.empty()) throw InputError(where + ": no frames");
  return FrameFiles(std::move(files));
}

}  // namespace

std::string FrameFiles::operator[](std::size_t i) const
{
  if (pattern_.empty()) return files_.at(i);
  if (i >= count_) throw std::out_of_range("frame " + std::to_string(i) + " of " + std::to_string(count_));
  const long number = first_ + long(i);
  std::string name(std::size_t(std::snprintf(nullptr, 0, pattern_.c_str(), int(number))), '\0');
  std::snprintf(name.data(), name.size() + 1, pattern_.c_str(), int(number));
  return resolve(base_, name);
}

Scene scene_from_frames(const std::vector<std::string>& frame_files, bool split)
{
  if (frame_files.empty()) throw InputError("a scene needs at least one frame file");
  Scene scene;
  const std::string& first = frame_files.front();
  scene.name = first.substr(first.rfind('/') + 1);
  SceneObject o;
  o.name = "mesh";
  o.frame_files = frame_files;
  add_objects(scene, *scene.cache_, std::move(o), split);
  return scene;
}

Scene load_scene(const std::string& path)
{
  const auto dot = path.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : path.substr(dot + 1);
  if (ext == "ply" || ext == "obj") {
    Scene scene = scene_from_frames({path});
    scene.objects[0].kind = ObjectKind::static_;
    return scene;
  }
  std::ifstream file = open_input(path, "scene manifest");
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError(path + ": read error");
  return parse_scene_manifest(text.str(), path);
}

Scene parse_scene_manifest(const std::string& text, const std::string& path)
{
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not valid JSON: " + e.what());
  }
  const std::string base = folder_of(path);
  Scene scene;
  try {
    scene.name = manifest.value("name", path.substr(path.rfind('/') + 1));
    if (!manifest.contains("objects") || !manifest["objects"].is_array() || manifest["objects"].empty())
      throw InputError(path + ": a manifest needs a non-empty \"objects\" list");
    for (std::size_t i = 0; i < manifest["objects"].size(); ++i) {
      const auto& o = manifest["objects"][i];
      SceneObject object;
      object.name = o.value("name", "object" + std::to_string(i));
      const std::string where = path + ": object " + object.name;
      try {
        object.kind = parse_object_kind(o.value("kind", "deformable"));
      } catch (const InputError& e) {
        throw InputError(where + ": " + e.what());
      }
      object.self_collision = o.value("self_collision", object.kind == ObjectKind::deformable);
      if (!o.contains("frames")) throw InputError(where + ": no \"frames\"");
      object.frame_files = frame_list(o["frames"], base, where);
      if (object.kind == ObjectKind::static_ && object.frame_files.size() != 1)
        throw InputError(where + ": a static object has exactly one frame");
      add_objects(scene, *scene.cache_, std::move(object), o.value("split_components", false));
    }
    std::size_t frames = 0;
    for (const auto& o : scene.objects) {
      if (o.kind == ObjectKind::static_) continue;
      if (frames && o.frame_files.size() != frames)
        throw InputError(path + ": object " + o.name + " has " + std::to_string(o.frame_files.size()) +
                         " frames, others have " + std::to_string(frames));
      frames = o.frame_files.size();
    }
    for (const auto& pair : manifest.value("ignore_pairs", nlohmann::json::array())) {
      if (!pair.is_array() || pair.size() != 2) throw InputError(path + ": \"ignore_pairs\" holds pairs of object names");
      std::uint32_t a = scene.object_index(pair[0].get<std::string>()), b = scene.object_index(pair[1].get<std::string>());
      scene.ignored_pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": " + e.what());
  }
  return scene;
}

}  // namespace cstreams
