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
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <tuple>

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
  bool no_escalation = false;
  int repeat = 5;
  std::string device;
  std::vector<std::string> devices;
  std::string json;
  std::string plot;
};

struct Row {
  std::string device, dataset, kind, solver, precision;
  double tolerance = 0;
  std::size_t queries = 0, positives = 0, false_negatives = 0, false_positives = 0, filtered = 0, limits = 0;
  std::size_t toi_known = 0, toi_late = 0;
  double toi_error_max = 0, toi_error_median = 0, ns_per_query = 0;
  // The earliest time reported, and the earliest exact time of the queries whose time is
  // known (NaN: none): a simulator backs up to the first, and stalls where it is 0 and
  // the second is not.
  double earliest = std::numeric_limits<double>::quiet_NaN(), exact_earliest = std::numeric_limits<double>::quiet_NaN();
  std::vector<bool> answers;  // per query: collides
};

// A device whose profiling events do not time kernels (rusticl) gets NaN for its time.
Row measure(DeviceSolver& solver, const runtime::DeviceInfo& device, const Dataset& d, int repeat)
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
  row.device = device.name;
  row.dataset = d.name;
  row.kind = d.kind == ContactKind::vertex_face ? "vf" : "ee";
  row.solver = to_string(solver.options().solver);
  row.precision = to_string(solver.options().precision);
  row.tolerance = solver.options().tolerance;
  row.queries = d.queries.size();
  row.positives = d.positives();
  row.ns_per_query = d.queries.empty() ? 0 : double(times[times.size() / 2]) / double(d.queries.size());
  if (!device.profiling_timer) row.ns_per_query = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> errors;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    row.filtered += r.status == QueryStatus::filtered;
    row.limits += r.status == QueryStatus::limit;
    row.answers.push_back(r.collides());
    if (r.collides() && !(r.toi >= row.earliest)) row.earliest = r.toi;
    if (!std::isnan(d.exact_toi[i]) && !(double(d.exact_toi[i]) >= row.exact_earliest))
      row.exact_earliest = double(d.exact_toi[i]);
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
  const bool timed = !std::isnan(r.ns_per_query);
  return {{"device", r.device},
          {"dataset", r.dataset},
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
          {"earliest", std::isnan(r.earliest) ? nlohmann::json() : nlohmann::json(r.earliest)},
          {"exact_earliest", std::isnan(r.exact_earliest) ? nlohmann::json() : nlohmann::json(r.exact_earliest)},
          {"ns_per_query", timed ? nlohmann::json(r.ns_per_query) : nlohmann::json()},
          {"queries_per_second", !timed ? nlohmann::json() : nlohmann::json(r.ns_per_query > 0 ? 1e9 / r.ns_per_query : 0.0)}};
}

void print_row(const Row& r)
{
  char toi[64] = "-";
  if (r.toi_known) std::snprintf(toi, sizeof toi, "%.2e / %.2e / %zu", r.toi_error_max, r.toi_error_median, r.toi_late);
  char ns[32] = "-";
  if (!std::isnan(r.ns_per_query)) std::snprintf(ns, sizeof ns, "%.1f", r.ns_per_query);
  std::printf("| %-36s | %-2s | %-12s | %-6s | %7.0e | %7zu | %6zu | %4zu | %6zu | %7zu | %5zu | %-27s | %9s |\n",
              r.dataset.c_str(), r.kind.c_str(), r.solver.c_str(), r.precision.c_str(), r.tolerance, r.queries,
              r.positives, r.false_negatives, r.false_positives, r.filtered, r.limits, toi, ns);
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

// The earliest time of the sets whose exact times are known (the real steps') against
// the exact one.
void print_earliest(const std::vector<Row>& rows)
{
  bool header = false;
  for (const Row& r : rows) {
    if (std::isnan(r.exact_earliest)) continue;
    if (!header) std::printf("\nearliest time against the exact one (sets with exact times):\n");
    header = true;
    std::printf("  %-36s %-2s %-12s %-6s %13.7g / %-13.7g (%.4f of it)\n", r.dataset.c_str(), r.kind.c_str(),
                r.solver.c_str(), r.precision.c_str(), r.earliest, r.exact_earliest,
                r.exact_earliest > 0 ? r.earliest / r.exact_earliest : r.earliest == 0 ? 1.0 : 0.0);
  }
  std::printf("\n");
}

// One device's table: every solver, precision and tolerance asked for, on every dataset.
std::vector<Row> run_on(const std::string& filter, const AccuracyOptions& o, const std::vector<Dataset>& datasets,
                        nlohmann::json& out)
{
  runtime::Context context(filter);
  const runtime::DeviceInfo& device = context.device();
  std::vector<Solver> solvers;
  if (o.solver == "all") solvers = {Solver::cubic, Solver::conservative};
  else solvers = {parse_solver(o.solver)};
  std::vector<Precision> precisions;
  if (o.precision == "all") {
    precisions = {Precision::single};
    if (device.fp64) precisions.push_back(Precision::double_);
  } else {
    precisions = {parse_precision(o.precision)};
  }

  std::printf("device: %s (%s)%s\n\n", device.name.c_str(), device.platform_name.c_str(),
              device.profiling_timer ? "" : "; it does not time kernels");
  std::printf("| %-36s | %-2s | %-12s | %-6s | %7s | %7s | %6s | %4s | %6s | %7s | %5s | %-27s | %9s |\n", "dataset",
              "k", "solver", "prec", "tol", "queries", "pos", "FN", "FP", "culled", "limit",
              "toi err max / median / late", "ns/query");
  std::printf("|%s|\n", std::string(186, '-').c_str());
  if (out.empty()) {
    out = {{"device", device.name}, {"platform", device.platform_name}, {"results", nlohmann::json::array()}};
  }
  out["devices"].push_back({{"filter", filter}, {"device", device.name}, {"platform", device.platform_name}});
  std::vector<Row> rows;
  for (Solver s : solvers)
    for (Precision p : precisions) {
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
        options.escalate = !o.no_escalation;
        DeviceSolver solver(context, options);
        for (const auto& d : datasets) {
          rows.push_back(measure(solver, device, d, o.repeat));
          print_row(rows.back());
          out["results"].push_back(to_json(rows.back()));
        }
      }
    }
  print_earliest(rows);
  return rows;
}

// Several devices side by side: false negatives and false positives per solver,
// precision, tolerance and kind, summed over the datasets, and how many queries each
// device answers otherwise than the first.
void print_devices_side_by_side(const std::vector<std::vector<Row>>& per_device)
{
  using Key = std::tuple<std::string, std::string, double, std::string>;
  struct Cell {
    std::size_t false_negatives = 0, false_positives = 0, differing = 0;
    bool compared = true;  // device 1 ran every dataset of this cell too
  };
  std::map<Key, std::vector<std::optional<Cell>>> table;
  std::map<std::tuple<Key, std::string>, const std::vector<bool>*> first_answers;
  for (std::size_t d = 0; d < per_device.size(); ++d)
    for (const Row& r : per_device[d]) {
      const Key key{r.solver, r.precision, r.tolerance, r.kind};
      auto& cells = table[key];
      cells.resize(per_device.size());
      if (!cells[d]) cells[d] = Cell{};
      cells[d]->false_negatives += r.false_negatives;
      cells[d]->false_positives += r.false_positives;
      const std::tuple<Key, std::string> query_set{key, r.dataset};
      if (d == 0) {
        first_answers[query_set] = &r.answers;
        cells[d]->compared = false;
        continue;
      }
      const auto first = first_answers.find(query_set);
      if (first == first_answers.end()) {
        cells[d]->compared = false;
        continue;
      }
      for (std::size_t i = 0; i < r.answers.size(); ++i) cells[d]->differing += r.answers[i] != (*first->second)[i];
    }
  std::printf("per device: false negatives / false positives / queries answered otherwise than device 1\n");
  for (std::size_t d = 0; d < per_device.size(); ++d)
    if (!per_device[d].empty()) std::printf("  device %zu: %s\n", d + 1, per_device[d].front().device.c_str());
  std::printf("\n");
  std::printf("| %-12s | %-6s | %7s | %-2s |", "solver", "prec", "tol", "k");
  for (std::size_t d = 0; d < per_device.size(); ++d) std::printf(" device %-16zu |", d + 1);
  std::printf("\n");
  for (const auto& [key, cells] : table) {
    const auto& [solver, precision, tolerance, kind] = key;
    std::printf("| %-12s | %-6s | %7.0e | %-2s |", solver.c_str(), precision.c_str(), tolerance, kind.c_str());
    for (const auto& c : cells) {
      char text[32] = "-";
      if (c && c->compared)
        std::snprintf(text, sizeof text, "%zu / %zu / %zu", c->false_negatives, c->false_positives, c->differing);
      else if (c)
        std::snprintf(text, sizeof text, "%zu / %zu / -", c->false_negatives, c->false_positives);
      std::printf(" %-23s |", text);
    }
    std::printf("\n");
  }
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
  std::vector<std::string> filters = o.devices;
  if (filters.empty()) filters.push_back(o.device.empty() ? filter_from_environment() : o.device);
  nlohmann::json out;
  std::vector<std::vector<Row>> per_device;
  for (const auto& filter : filters) per_device.push_back(run_on(filter, o, datasets, out));
  if (per_device.size() > 1) print_devices_side_by_side(per_device);
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
  cmd->add_flag("--no-filter", o->no_filter, "Do not run the non-penetration filter");
  cmd->add_flag("--no-escalation", o->no_escalation,
                "Single precision: report the contacts float cannot prove as they are, rather than deciding them "
                "again in double");
  cmd->add_option("--repeat", o->repeat, "Timed repeats after one warm-up (median reported)")->check(CLI::PositiveNumber);
  auto* device = cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_option("--devices", o->devices,
                  "Device filters, one per device: each device's table, then false negatives and positives side "
                  "by side")
      ->excludes(device);
  cmd->add_option("--json", o->json, "Write the results as JSON");
  cmd->add_option("--plot", o->plot, "Draw speed against error as a PNG (python3-matplotlib)");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { run(*o); };
  });
}

}  // namespace cstreams::cli
