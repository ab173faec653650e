#pragma once
#include <cstreams/contacts.hpp>
#include <cstreams/reference/reference_solver.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace cstreams {

// A set of elementary queries of one kind with exact ground truth.
struct Dataset {
  std::string name;  // e.g. "handmade/erleben-spikes" or "rod-twist/3036"
  ContactKind kind = ContactKind::vertex_face;
  std::vector<Query> queries;
  std::vector<bool> collides;          // exact truth per query
  std::vector<long double> exact_toi;  // earliest exact contact per query; NaN where unknown
  // Real steps only: each query's features in the mesh's own ids, (vertex, face) or
  // (edge, edge) in the mesh's edge order; empty for other sets.
  std::vector<std::array<std::uint32_t, 2>> features;
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

// The ground truth of one real step for contacts of the one-object scene its two
// frames make (as `cstreams run A.ply B.ply` loads them).
class StepTruth {
public:
  struct Answer {
    bool collides = false;
    long double exact_toi = 0;  // NaN where unknown

    // What the truth says of a reported time (none: not reported): a contact that
    // happens must be reported, no later than the exact time where that is known; one
    // that does not must not be. "right", "misses it", "later than exact" or "false
    // positive".
    const char* verdict(const std::optional<double>& toi) const;
  };

  // The truth of the step whose frames/ holds both files, or none where they are not
  // the two frames of a real step folder (frames/, boxes/, mma_bool/).
  static std::optional<StepTruth> for_frames(const std::vector<std::string>& frame_paths);
  // None where the step's candidate list does not hold the contact's features.
  std::optional<Answer> of(const Contact& contact) const;

private:
  using Key = std::tuple<ContactKind, std::uint32_t, std::uint32_t>;
  std::map<Key, Answer> answers_;
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> face_of_;
  std::map<std::array<std::uint32_t, 2>, std::uint32_t> edge_of_;
};

}  // namespace cstreams
