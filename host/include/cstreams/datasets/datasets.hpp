#pragma once
#include <cstreams/contacts.hpp>
#include <cstreams/reference/reference_solver.hpp>

#include <string>
#include <vector>

namespace cstreams {

// A set of elementary queries of one kind with exact ground truth.
struct Dataset {
  std::string name;  // e.g. "handmade/erleben-spikes" or "rod-twist/3036"
  ContactKind kind = ContactKind::vertex_face;
  std::vector<Query> queries;
  std::vector<bool> collides;          // exact truth per query
  std::vector<long double> exact_toi;  // earliest exact contact per query; NaN where unknown
  std::size_t positives() const;
};

// Finds every dataset under `path`, which may be:
//   - a folder of the hand-made set (with vertex-face/ and edge-edge/ of Format A CSVs,
//     truth in the seventh column), or a folder holding several;
//   - a real simulation step (frames/, boxes/, mma_bool/): queries are rebuilt from the
//     frames and the box ids with the documented id convention, truth from mma_bool,
//     exact times from toi-ground-truth/ when it is found above;
//   - a folder holding several of the above at any depth (e.g. scenes/benchmarks);
//   - one Format A CSV file.
// Throws InputError when nothing is found.
std::vector<Dataset> discover_datasets(const std::string& path);

// Rebuilds the queries of a real step in the order of its boxes/ file.
Dataset real_step_dataset(const std::string& step_folder, ContactKind kind);

}  // namespace cstreams
