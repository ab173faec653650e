#pragma once
#include <cstreams/contacts.hpp>
#include <cstreams/reference/reference_solver.hpp>
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/program_registry.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cstreams {

namespace runtime {
class Context;
}

enum class Solver {
  cubic,        // the paper's coplanarity cubic + Newton + inside test; can miss contacts
  conservative  // interval inclusion; never misses a contact
};
enum class Precision { single, double_ };
const char* to_string(Solver s) noexcept;
const char* to_string(Precision p) noexcept;
Solver parse_solver(const std::string& text);
Precision parse_precision(const std::string& text);

// Settings of the elementary tests, with the defaults a user should start from.
struct SolverOptions {
  Solver solver = Solver::conservative;
  Precision precision = Precision::single;
  // Relative to the query's largest coordinate. Conservative: the co-domain tolerance
  // (smaller: fewer false positives and a tighter time, more work). Cubic: how close
  // the features must come at a root to count as touching.
  double tolerance = 1e-5;
  // Pairs closer than this (scene units) collide. Conservative solver only.
  double min_separation = 0;
  // The conservative solver's work limit per query; reaching it reports a collision
  // at the earliest time still possible.
  std::uint32_t max_iterations = 100000;
  // Cull pairs the deforming non-penetration filter proves separate (never a true
  // contact) before solving. Not applied with a minimum separation.
  bool filter = true;
  // Conservative solver in single precision without a minimum separation, on a device
  // with double: a contact whose float enclosure cannot prove an exact zero (one no
  // later than twice the time it reports) is decided again in double, that query
  // alone. Without it, near misses closer than float's rounding are contacts, and such
  // a pair can report time 0.
  bool escalate = true;
};

// Throws InputError naming the first option out of range (option_checks.hpp), or the
// device's missing double precision.
void check_solver_options(const runtime::Context& context, const SolverOptions& options);

enum class QueryStatus : std::uint32_t {
  separate = 0,  // no contact in [0, 1]
  collides = 1,
  filtered = 2,  // separate, proven by the non-penetration filter
  limit = 3      // reported as colliding because a solver limit was reached
};

struct ElementaryResult {
  QueryStatus status = QueryStatus::separate;
  double toi = 1;
  bool collides() const { return status == QueryStatus::collides || status == QueryStatus::limit; }
};

// Runs one solver over batches of queries on a device, through the same passes as the
// pipeline's elementary tests (each query laid out as a candidate pair of its own).
// Its graphs (one per kind) and buffers are kept and grow only.
class DeviceSolver {
public:
  DeviceSolver(runtime::Context& context, const SolverOptions& options);
  ~DeviceSolver();
  DeviceSolver(const DeviceSolver&) = delete;
  DeviceSolver& operator=(const DeviceSolver&) = delete;

  // Uploads, solves and reads back. *kernel_ns receives the kernel's device time.
  std::vector<ElementaryResult> solve(ContactKind kind, const std::vector<Query>& queries,
                                      std::uint64_t* kernel_ns = nullptr);
  const SolverOptions& options() const { return options_; }

private:
  struct Graph;
  Graph& graph(ContactKind kind);

  runtime::Context& context_;
  SolverOptions options_;
  std::unique_ptr<Graph> graphs_[2];
};

// Build options of the elementary-test kernels for these settings (precision, solver,
// search stack, subnormal flushing in single precision).
std::string solver_build_options(const SolverOptions& options);

// One float step above the float nearest to x (0 and below give 0): how a double
// tolerance or separation is handed to float kernels, never stricter than asked.
float float_above(double x);

// The OpenCL sources of the collision kernels (cl_kernels/ccd), for a program registry.
const runtime::SourceSet& ccd_kernel_sources();

}  // namespace cstreams
