#include "commands.hpp"
#include "plotting.hpp"

#include <cstreams/datasets/datasets.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>

extern const char* const cstreams_plot_accuracy_script;

namespace cstreams::cli {

namespace {

struct AccuracyOptions {
  std::vector<std::string> queries;
  std::string solver = "all";
  std::string precision = "all";
  std::vector<double> tolerances;
  double min_separation = 0;
  std::uint32_t max_iterations = SolverOptions{}.max_iterations;
  bool no_filter = false;
  int repeat = 5;
  std::string device;
  std::string json;
  std::string plot;
};

struct Row {
  std::string dataset, kind, solver, precision;
  double tolerance = 0;
  std::size_t queries = 0, positives = 0, false_negatives = 0, false_positives = 0, filtered = 0, limits = 0;
  std::size_t toi_known = 0, toi_late = 0;
  double toi_error_max = 0, toi_error_median = 0, ns_per_query = 0;
};

Row measure(DeviceSolver& solver, const Dataset& d, int repeat)
{
  std::vector<std::uint64_t> times;
  std::vector<ElementaryResult> results;
  for (int r = 0; r <= repeat; ++r) {  // the first run is the warm-up
    std::uint64_t ns = 0;
    results = solver.solve(d.kind, d.queries, &ns);
    if (r > 0) times.push_back(ns);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  Row row;
  row.dataset = d.name;
  row.kind = d.kind == ContactKind::vertex_face ? "vf" : "ee";
  row.solver = to_string(solver.options().solver);
  row.precision = to_string(solver.options().precision);
  row.tolerance = solver.options().tolerance;
  row.queries = d.queries.size();
  row.positives = d.positives();
  row.ns_per_query = d.queries.empty() ? 0 : double(times[times.size() / 2]) / double(d.queries.size());
  std::vector<double> errors;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    row.filtered += r.status == QueryStatus::filtered;
    row.limits += r.status == QueryStatus::limit;
    if (d.collides[i] && !r.collides()) ++row.false_negatives;
    if (!d.collides[i] && r.collides()) ++row.false_positives;
    if (d.collides[i] && r.collides() && !std::isnan(d.exact_toi[i])) {
      const long double error = (long double)r.toi - d.exact_toi[i];
      row.toi_late += error > 0;
      errors.push_back(double(std::fabs(error)));
    }
  }
  row.toi_known = errors.size();
  if (!errors.empty()) {
    row.toi_error_max = *std::max_element(errors.begin(), errors.end());
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    row.toi_error_median = errors[errors.size() / 2];
  }
  return row;
}

nlohmann::json to_json(const Row& r)
{
  nlohmann::json toi_max = r.toi_known ? nlohmann::json(r.toi_error_max) : nlohmann::json();
  nlohmann::json toi_median = r.toi_known ? nlohmann::json(r.toi_error_median) : nlohmann::json();
  return {{"dataset", r.dataset},
          {"kind", r.kind},
          {"solver", r.solver},
          {"precision", r.precision},
          {"tolerance", r.tolerance},
          {"queries", r.queries},
          {"positives", r.positives},
          {"false_negatives", r.false_negatives},
          {"false_positives", r.false_positives},
          {"filtered", r.filtered},
          {"limits", r.limits},
          {"toi_known", r.toi_known},
          {"toi_error_max", toi_max},
          {"toi_error_median", toi_median},
          {"toi_later_than_exact", r.toi_late},
          {"ns_per_query", r.ns_per_query},
          {"queries_per_second", r.ns_per_query > 0 ? 1e9 / r.ns_per_query : 0.0}};
}

void print_row(const Row& r)
{
  char toi[64] = "-";
  if (r.toi_known) std::snprintf(toi, sizeof toi, "%.2e / %.2e / %zu", r.toi_error_max, r.toi_error_median, r.toi_late);
  std::printf("| %-36s | %-2s | %-12s | %-6s | %7.0e | %7zu | %6zu | %4zu | %6zu | %7zu | %5zu | %-27s | %9.1f |\n",
              r.dataset.c_str(), r.kind.c_str(), r.solver.c_str(), r.precision.c_str(), r.tolerance, r.queries,
              r.positives, r.false_negatives, r.false_positives, r.filtered, r.limits, toi, r.ns_per_query);
  std::fflush(stdout);
}

void write_file(const std::string& path, const std::string& text)
{
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

void check(const AccuracyOptions& o)
{
  for (double tolerance : o.tolerances) check_option("--tolerance", tolerance, option_ranges::tolerance);
  check_option("--min-separation", o.min_separation, option_ranges::min_separation);
  check_option("--max-iterations", o.max_iterations, option_ranges::max_iterations);
  if (!o.json.empty()) check_output_path("--json", o.json);
  if (!o.plot.empty()) check_output_path("--plot", o.plot);
}

void run(const AccuracyOptions& o)
{
  std::vector<std::string> roots = o.queries;
  if (roots.empty()) roots.push_back(CSTREAMS_DEFAULT_BENCHMARK_DIR);
  std::vector<Dataset> datasets;
  for (const auto& root : roots) {
    auto found = discover_datasets(root);
    datasets.insert(datasets.end(), std::make_move_iterator(found.begin()), std::make_move_iterator(found.end()));
  }
  runtime::Context context(o.device.empty() ? filter_from_environment() : o.device);

  std::vector<Solver> solvers;
  if (o.solver == "all") solvers = {Solver::cubic, Solver::conservative};
  else solvers = {parse_solver(o.solver)};
  std::vector<Precision> precisions;
  if (o.precision == "all") {
    precisions = {Precision::single};
    if (context.device().fp64) precisions.push_back(Precision::double_);
  } else {
    precisions = {parse_precision(o.precision)};
  }

  std::printf("device: %s (%s)\n\n", context.device().name.c_str(), context.device().platform_name.c_str());
  std::printf("| %-36s | %-2s | %-12s | %-6s | %7s | %7s | %6s | %4s | %6s | %7s | %5s | %-27s | %9s |\n", "dataset",
              "k", "solver", "prec", "tol", "queries", "pos", "FN", "FP", "culled", "limit",
              "toi err max / median / late", "ns/query");
  std::printf("|%s|\n", std::string(186, '-').c_str());
  nlohmann::json out{{"device", context.device().name}, {"platform", context.device().platform_name},
                     {"results", nlohmann::json::array()}};
  for (Solver s : solvers)
    for (Precision p : precisions) {
      // What the device lacks for this pair is said once, not failed on.
      if (o.precision == "all" && p == Precision::double_ && s == Solver::conservative && !context.device().int64_atomics) {
        std::printf("| conservative double skipped: %s has no 64-bit atomics |\n", context.device().name.c_str());
        continue;
      }
      std::vector<double> tolerances = o.tolerances;
      if (tolerances.empty()) tolerances = {SolverOptions{}.tolerance};
      for (double tolerance : tolerances) {
        SolverOptions options;
        options.solver = s;
        options.precision = p;
        options.tolerance = tolerance;
        options.min_separation = o.min_separation;
        options.max_iterations = o.max_iterations;
        options.filter = !o.no_filter;
        DeviceSolver solver(context, options);
        for (const auto& d : datasets) {
          const Row row = measure(solver, d, o.repeat);
          print_row(row);
          out["results"].push_back(to_json(row));
        }
      }
    }
  if (!o.json.empty()) write_file(o.json, out.dump(2) + "\n");
  if (!o.plot.empty()) draw_plot(cstreams_plot_accuracy_script, out, o.plot);
}

}  // namespace

void add_accuracy_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<AccuracyOptions>();
  auto* cmd = app.add_subcommand("accuracy",
                                 "Measure the elementary solvers on the device: errors against exact ground truth, and speed");
  cmd->add_option("--queries", o->queries,
                  "Query file or folder (hand-made CSVs, a simulation step, or a folder of them); default: every "
                  "dataset in the benchmark data (scenes/benchmarks)");
  cmd->add_option("--solver", o->solver, "cubic, conservative or all")->check(CLI::IsMember({"cubic", "conservative", "all"}));
  cmd->add_option("--precision", o->precision, "single, double or all (double only where the device has fp64)")
      ->check(CLI::IsMember({"single", "double", "all"}));
  cmd->add_option("--tolerance", o->tolerances, "Solver tolerance(s), relative; several draw a sweep");
  cmd->add_option("--min-separation", o->min_separation, "Minimum separation (conservative solver)");
  cmd->add_option("--max-iterations", o->max_iterations, "Conservative solver's work limit per query");
  cmd->add_flag("--no-filter", o->no_filter, "Do not run the non-penetration filter first");
  cmd->add_option("--repeat", o->repeat, "Timed repeats after one warm-up (median reported)")->check(CLI::PositiveNumber);
  cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_option("--json", o->json, "Write the results as JSON");
  cmd->add_option("--plot", o->plot, "Draw speed against error as a PNG (python3-matplotlib)");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { run(*o); };
  });
}

}  // namespace cstreams::cli
