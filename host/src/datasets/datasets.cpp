#include <cstreams/datasets/datasets.hpp>
#include <cstreams/io/file_input.hpp>
#include <cstreams/io/query_io.hpp>
#include <cstreams/reference/reference_ccd.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace cstreams {

namespace fs = std::filesystem;

std::size_t Dataset::positives() const { return std::size_t(std::count(collides.begin(), collides.end(), true)); }

namespace {

const char* kind_suffix(ContactKind k) { return k == ContactKind::vertex_face ? "vf" : "ee"; }

Dataset csv_dataset(const fs::path& file, const std::string& name, ContactKind kind)
{
  Dataset d;
  d.name = name;
  d.kind = kind;
  for (auto& q : read_queries(file.string())) {
    d.queries.push_back(q.points);
    d.collides.push_back(q.collides);
  }
  d.exact_toi.assign(d.queries.size(), std::nanl(""));
  return d;
}

void handmade(const fs::path& folder, std::vector<Dataset>& out)
{
  for (const auto& [sub, kind] : {std::pair{"vertex-face", ContactKind::vertex_face}, {"edge-edge", ContactKind::edge_edge}}) {
    const fs::path dir = folder / sub;
    if (!fs::is_directory(dir)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".csv") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    Dataset all;
    all.name = "handmade/" + folder.filename().string();
    all.kind = kind;
    for (const auto& f : files) {
      Dataset d = csv_dataset(f, all.name, kind);
      all.queries.insert(all.queries.end(), d.queries.begin(), d.queries.end());
      all.collides.insert(all.collides.end(), d.collides.begin(), d.collides.end());
      all.exact_toi.insert(all.exact_toi.end(), d.exact_toi.begin(), d.exact_toi.end());
    }
    if (!all.queries.empty()) out.push_back(std::move(all));
  }
}

// toi-ground-truth/, searched for from the step folder upwards.
fs::path toi_folder(fs::path from)
{
  for (from = fs::absolute(from); !from.empty(); from = from.parent_path()) {
    const fs::path candidate = from / "toi-ground-truth";
    if (fs::is_directory(candidate)) return candidate;
    if (from == from.parent_path()) break;
  }
  return {};
}

std::string step_prefix(const fs::path& folder)
{
  for (const auto& e : fs::directory_iterator(folder / "boxes")) {
    const std::string name = e.path().filename().string();
    if (name.size() > 7 && name.substr(name.size() - 7) == "vf.json") return name.substr(0, name.size() - 7);
  }
  throw InputError(folder.string() + ": boxes/ holds no <step>vf.json");
}

// The one-object scene of a real step's two frames.
Scene step_scene(const fs::path& folder)
{
  std::vector<std::string> frames;
  for (const auto& e : fs::directory_iterator(folder / "frames")) frames.push_back(e.path().string());
  // Frame files are named by number; order them numerically, not by text.
  auto number = [](const std::string& path) {
    const std::string stem = fs::path(path).stem().string();
    std::size_t end = stem.size(), begin = end;
    while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
    return begin < end ? std::stol(stem.substr(begin, end - begin)) : 0L;
  };
  std::sort(frames.begin(), frames.end(), [&](const auto& a, const auto& b) { return number(a) < number(b); });
  if (frames.size() != 2) throw InputError(folder.string() + ": expected two frames in frames/");
  return scene_from_frames(frames);
}

// The queries of one kind of a real step whose scene is loaded, in the order of its
// boxes/ file.
Dataset step_dataset(const fs::path& folder, const Scene& scene, ContactKind kind)
{
  const std::string step = step_prefix(folder);
  const Step s = load_step(scene, 0);
  const Topology& t = scene.objects[0].topology;
  const std::uint64_t nv = t.vertex_count, ne = t.edges.size(), nf = t.faces.size();

  Dataset d;
  d.name = folder.filename().string() + "/" + step;
  d.kind = kind;
  const std::string boxes_file = (folder / "boxes" / (step + kind_suffix(kind) + ".json")).string();
  std::ifstream in = open_input(boxes_file, "candidate list");
  std::vector<std::array<std::uint64_t, 2>> boxes;
  try {
    boxes = nlohmann::json::parse(in).get<std::vector<std::array<std::uint64_t, 2>>>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(boxes_file + ": " + e.what());
  }
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const auto [a, b] = boxes[i];
    if (kind == ContactKind::vertex_face) {
      if (a >= nv || b < nv + ne || b >= nv + ne + nf)
        throw InputError(boxes_file + ": pair " + std::to_string(i) + " is not a vertex and a face");
      d.queries.push_back(vertex_face_query(s, 0, 0, {std::uint32_t(a), std::uint32_t(b - nv - ne)}));
      d.features.push_back({std::uint32_t(a), std::uint32_t(b - nv - ne)});
    } else {
      if (a < nv || a >= nv + ne || b < nv || b >= nv + ne)
        throw InputError(boxes_file + ": pair " + std::to_string(i) + " is not two edges");
      d.queries.push_back(edge_edge_query(s, 0, 0, {std::uint32_t(a - nv), std::uint32_t(b - nv)}));
      d.features.push_back({std::uint32_t(a - nv), std::uint32_t(b - nv)});
    }
  }
  d.collides = read_bool_array((folder / "mma_bool" / (step + kind_suffix(kind) + "_mma_bool.json")).string());
  if (d.collides.size() != d.queries.size())
    throw InputError(folder.string() + ": mma_bool and boxes disagree in length for " + kind_suffix(kind));

  d.exact_toi.assign(d.queries.size(), std::nanl(""));
  const fs::path tois = toi_folder(folder);
  const fs::path toi_file = tois / (folder.filename().string() + "_" + step + kind_suffix(kind) + "_toi.csv");
  if (!tois.empty() && fs::exists(toi_file)) {
    std::ifstream tin = open_input(toi_file.string(), "time-of-impact file");
    std::string line;
    std::size_t line_number = 0;
    while (std::getline(tin, line)) {
      ++line_number;
      if (line.empty() || !std::isdigit(static_cast<unsigned char>(line[0]))) continue;  // header
      std::stringstream fields(line);
      std::string index, roots, toi;
      std::getline(fields, index, ',');
      std::getline(fields, roots, ',');
      std::getline(fields, toi, ',');
      const std::size_t q = std::stoul(index);
      if (q >= d.queries.size())
        throw InputError(toi_file.string() + ":" + std::to_string(line_number) + ": query " + index + " does not exist");
      d.exact_toi[q] = std::strtold(toi.c_str(), nullptr);
    }
  }
  return d;
}

}  // namespace

Dataset real_step_dataset(const std::string& step_folder, ContactKind kind)
{
  return step_dataset(step_folder, step_scene(step_folder), kind);
}

const char* StepTruth::Answer::verdict(const std::optional<double>& toi) const
{
  if (!collides) return toi ? "false positive" : "right";
  if (!toi) return "misses it";
  return !std::isnan(exact_toi) && (long double)*toi > exact_toi ? "later than exact" : "right";
}

std::optional<StepTruth> StepTruth::for_frames(const std::vector<std::string>& frame_paths)
{
  if (frame_paths.size() != 2) return std::nullopt;
  const fs::path frames = fs::absolute(frame_paths[0]).parent_path();
  if (frames.filename() != "frames" || fs::absolute(frame_paths[1]).parent_path() != frames) return std::nullopt;
  const fs::path folder = frames.parent_path();
  if (!fs::is_directory(folder / "boxes") || !fs::is_directory(folder / "mma_bool")) return std::nullopt;
  const Scene scene = step_scene(folder);
  StepTruth truth;
  for (auto kind : {ContactKind::vertex_face, ContactKind::edge_edge}) {
    const Dataset d = step_dataset(folder, scene, kind);
    for (std::size_t i = 0; i < d.features.size(); ++i) {
      auto [a, b] = d.features[i];
      if (kind == ContactKind::edge_edge && b < a) std::swap(a, b);
      truth.answers_[{kind, a, b}] = {d.collides[i], d.exact_toi[i]};
    }
  }
  // Ids as the step's datasets name them: the object's own topology.
  const Topology& t = scene.objects[0].topology;
  for (std::uint32_t f = 0; f < t.faces.size(); ++f) truth.face_of_[t.faces[f]] = f;
  for (std::uint32_t e = 0; e < t.edges.size(); ++e) truth.edge_of_[t.edges[e]] = e;
  return truth;
}

std::optional<StepTruth::Answer> StepTruth::of(const Contact& c) const
{
  if (c.object_a != 0 || c.object_b != 0) return std::nullopt;
  std::uint32_t a = 0, b = 0;
  if (c.kind == ContactKind::vertex_face) {
    const auto face = face_of_.find({c.v[1], c.v[2], c.v[3]});
    if (face == face_of_.end()) return std::nullopt;
    a = c.v[0];
    b = face->second;
  } else {
    const auto first = edge_of_.find({c.v[0], c.v[1]}), second = edge_of_.find({c.v[2], c.v[3]});
    if (first == edge_of_.end() || second == edge_of_.end()) return std::nullopt;
    a = std::min(first->second, second->second);
    b = std::max(first->second, second->second);
  }
  const auto answer = answers_.find({c.kind, a, b});
  if (answer == answers_.end()) return std::nullopt;
  return answer->second;
}

std::vector<Dataset> discover_datasets(const std::string& path)
{
  const fs::path p(path);
  std::vector<Dataset> out;
  if (fs::is_regular_file(p)) {
    const std::string text = p.string();
    const ContactKind kind = text.find("edge-edge") != std::string::npos || text.find("ee.csv") != std::string::npos
                                 ? ContactKind::edge_edge
                                 : ContactKind::vertex_face;
    out.push_back(csv_dataset(p, p.filename().string(), kind));
    return out;
  }
  if (!fs::is_directory(p)) throw InputError(path + ": no such query file or folder");
  if (fs::is_directory(p / "vertex-face") || fs::is_directory(p / "edge-edge")) {
    handmade(p, out);
  } else if (fs::is_directory(p / "frames") && fs::is_directory(p / "boxes") && fs::is_directory(p / "mma_bool")) {
    const Scene scene = step_scene(p);
    for (auto kind : {ContactKind::vertex_face, ContactKind::edge_edge}) out.push_back(step_dataset(p, scene, kind));
  } else {
    std::vector<fs::path> children;
    for (const auto& e : fs::directory_iterator(p))
      if (e.is_directory()) children.push_back(e.path());
    std::sort(children.begin(), children.end());
    for (const auto& c : children) {
      try {
        auto found = discover_datasets(c.string());
        out.insert(out.end(), std::make_move_iterator(found.begin()), std::make_move_iterator(found.end()));
      } catch (const InputError& e) {
        if (std::string(e.what()).find("nothing to measure") == std::string::npos) throw;
      }
    }
  }
  if (out.empty()) throw InputError(path + ": nothing to measure: no query files or simulation steps found");
  return out;
}

}  // namespace cstreams
