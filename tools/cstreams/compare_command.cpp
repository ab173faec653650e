#include "commands.hpp"
#include "measurement.hpp"
#include "plotting.hpp"

#include <cstreams/datasets/datasets.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/pipeline/option_checks.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <tuple>

extern const char* const cstreams_plot_compare_script;

namespace cstreams::cli {

namespace {

struct CompareOptions : MeasureOptions {
  std::vector<std::string> devices;
  std::string json;
  std::string plot;
};

// A contact's identity across devices: the step and the feature pair.
using ContactKey = std::tuple<std::size_t, ContactKind, std::uint32_t, std::uint32_t, std::array<std::uint32_t, 4>>;

// Each contact any device reports, with every device's time of impact (none where a
// device does not report it); kept only where the devices disagree.
std::map<ContactKey, std::vector<std::optional<double>>> differences(const std::vector<Measurement>& runs,
                                                                       std::size_t first_frame)
{
  std::map<ContactKey, std::vector<std::optional<double>>> all;
  for (std::size_t d = 0; d < runs.size(); ++d) {
    std::size_t step = 0;
    for (std::size_t i = 0; i < runs[d].contacts.size(); ++i) {
      while (i >= runs[d].step_ends[step]) ++step;
      const Contact& c = runs[d].contacts[i];
      auto& times = all[{first_frame + step, c.kind, c.object_a, c.object_b, c.v}];
      times.resize(runs.size());
      times[d] = c.toi;
    }
  }
  for (auto it = all.begin(); it != all.end();) {
    const auto& t = it->second;
    bool same = true;
    for (const auto& x : t) same = same && x.has_value() && *x == *t[0];
    it = same ? all.erase(it) : std::next(it);
  }
  return all;
}

void print_row(const char* name, const std::vector<double>& values, const char* format)
{
  std::printf("  %-44s", name);
  for (double v : values)
    if (std::isnan(v)) std::printf(" %12s", "-");  // a device that does not time kernels
    else std::printf(format, v);
  for (std::size_t d = 1; d < values.size(); ++d)
    if (values[0] > 0 && !std::isnan(values[d])) std::printf(" %11.3gx", values[d] / values[0]);
    else std::printf(" %12s", "-");
  std::printf("\n");
}

Contact contact_of(const ContactKey& key)
{
  const auto& [frame, kind, a, b, v] = key;
  return Contact{kind, a, b, v, 0};
}

void print_difference(const ContactKey& key, const std::vector<std::optional<double>>& times,
                      const std::optional<StepTruth::Answer>& truth)
{
  const auto& [frame, kind, a, b, v] = key;
  std::printf("  step %zu %s objects %u-%u (%u %u %u %u):", frame, kind == ContactKind::vertex_face ? "vf" : "ee", a, b,
              v[0], v[1], v[2], v[3]);
  for (const auto& t : times)
    if (t) std::printf(" %.17g", *t);
    else std::printf(" %17s", "none");
  std::printf("\n");
  if (!truth) return;
  if (!truth->collides) std::printf("    truth: no contact");
  else if (std::isnan(truth->exact_toi)) std::printf("    truth: contact");
  else std::printf("    truth: contact at %.17Lg", truth->exact_toi);
  for (std::size_t d = 0; d < times.size(); ++d) std::printf("; device %zu: %s", d + 1, truth->verdict(times[d]));
  std::printf("\n");
}

using Differences = std::map<ContactKey, std::vector<std::optional<double>>>;
using TruthOf = std::function<std::optional<StepTruth::Answer>(const ContactKey&)>;

// The scene, the devices, each pass's median side by side with the ratios to the first
// device, and the contacts that differ (the first 20).
void print_comparison(const CompareOptions& o, const Scene& scene, std::size_t first, std::size_t last,
                      std::vector<Measurement>& runs, const Differences& differing, bool with_truth,
                      const TruthOf& truth_of)
{
  std::printf("scene     %s: %zu objects, %zu faces; %zu steps (frames %zu to %zu)\n", scene.name.c_str(),
              scene.objects.size(), scene.face_count(), last - first, first, last);
  std::printf("solver    %s, %s precision, tolerance %g; front %s; medians of %u run(s) a step\n", o.solver.c_str(),
              o.precision.c_str(), o.tolerance, o.front.c_str(), o.repeat);
  for (std::size_t d = 0; d < runs.size(); ++d)
    std::printf("device %zu  %s: %s (%s)\n", d + 1, o.devices[d].c_str(), runs[d].device.c_str(),
                runs[d].platform.c_str());
  std::printf("\n  %-44s", "median device ms per pass");
  for (std::size_t d = 0; d < runs.size(); ++d) std::printf(" %11s%zu", "device ", d + 1);
  for (std::size_t d = 1; d < runs.size(); ++d) std::printf(" %10s%zu/1", "", d + 1);
  std::printf("\n");
  auto across = [&](auto value) {
    std::vector<double> v;
    for (auto& r : runs) v.push_back(value(r));
    return v;
  };
  for (const auto& pass : runs[0].pass_order)
    print_row(pass.c_str(), across([&](Measurement& r) { return median(r.pass_ms[pass]); }), " %12.3f");
  print_row("all passes (device ms)", across([](Measurement& r) { return median(r.device_ms); }), " %12.3f");
  print_row("step (wall ms)", across([](Measurement& r) { return median(r.host_ms); }), " %12.3f");
  print_row("device memory (MiB)", across([](Measurement& r) { return double(r.peak_bytes) / (1 << 20); }),
            " %12.1f");
  print_row("contacts", across([](Measurement& r) { return double(r.contacts.size()); }), " %12.0f");
  if (differing.empty()) {
    std::printf("\ncontacts  identical on every device\n");
    return;
  }
  std::printf("\ncontacts  %zu differ (time of impact per device, \"none\" where it reports none%s):\n",
              differing.size(), with_truth ? "; the step's ground truth below each" : "");
  std::size_t shown = 0;
  for (const auto& [key, times] : differing) {
    if (++shown > 20) {
      std::printf("  ... and %zu more (all in --json)\n", differing.size() - 20);
      break;
    }
    print_difference(key, times, truth_of(key));
  }
}

// Every device's figures and every contact that differs, with the step's truth.
nlohmann::json comparison_json(const CompareOptions& o, const Scene& scene, std::size_t first, std::size_t last,
                               std::vector<Measurement>& runs, const Differences& differing, const TruthOf& truth_of)
{
  nlohmann::json out{{"scene", scene.name},     {"solver", o.solver}, {"precision", o.precision},
                     {"tolerance", o.tolerance}, {"front", o.front},   {"first_frame", first},
                     {"last_frame", last},       {"repeat", o.repeat}, {"identical", differing.empty()},
                     {"difference_count", differing.size()}};
  for (std::size_t d = 0; d < runs.size(); ++d) {
    Measurement& r = runs[d];
    nlohmann::json passes = nlohmann::json::object();
    for (const auto& [name, ms] : r.pass_ms) passes[name] = median(ms);
    out["devices"].push_back({{"filter", o.devices[d]},
                              {"device", r.device},
                              {"platform", r.platform},
                              {"median_device_ms", median(r.device_ms)},
                              {"median_host_ms", median(r.host_ms)},
                              {"peak_bytes", r.peak_bytes},
                              {"contacts", r.contacts.size()},
                              {"passes", passes},
                              {"steps", r.steps}});
  }
  out["differences"] = nlohmann::json::array();
  for (const auto& [key, times] : differing) {
    const auto& [frame, kind, a, b, v] = key;
    nlohmann::json t = nlohmann::json::array();
    for (const auto& x : times) t.push_back(x ? nlohmann::json(*x) : nlohmann::json());
    nlohmann::json truth_json, verdicts;
    if (const auto answer = truth_of(key)) {
      const bool exact = !std::isnan(answer->exact_toi);
      truth_json = {{"collides", answer->collides},
                    {"exact_toi", exact ? nlohmann::json(double(answer->exact_toi)) : nlohmann::json()}};
      for (const auto& x : times) verdicts.push_back(answer->verdict(x));
    }
    out["differences"].push_back({{"frame", frame},
                                  {"kind", kind == ContactKind::vertex_face ? "vf" : "ee"},
                                  {"object_a", a},
                                  {"object_b", b},
                                  {"v", v},
                                  {"toi", t},
                                  {"truth", truth_json},
                                  {"verdicts", verdicts}});
  }
  return out;
}

void compare(const CompareOptions& o)
{
  const auto source = scene_source(o);
  const Scene& scene = source->scene;
  const auto [first, last] = resolve(parse_step_range(o.frames), scene.frame_count());

  std::vector<Measurement> runs;
  for (const auto& filter : o.devices) {
    runtime::Context context(filter);
    runs.push_back(measure(o, scene, first, last, context));
  }
  const Differences differing = differences(runs, first);
  // Ground truth where the scene is the one object of a real step's two frames.
  std::optional<StepTruth> truth;
  if (scene.objects.size() == 1 && first == 0 && last == 1 && !differing.empty())
    truth = StepTruth::for_frames(o.paths);
  const TruthOf truth_of = [&](const ContactKey& key) {
    return truth ? truth->of(contact_of(key)) : std::optional<StepTruth::Answer>{};
  };
  print_comparison(o, scene, first, last, runs, differing, bool(truth), truth_of);
  if (o.json.empty() && o.plot.empty()) return;
  const nlohmann::json out = comparison_json(o, scene, first, last, runs, differing, truth_of);
  if (!o.json.empty()) write_file_atomically(o.json, [&](std::ostream& f) { f << out.dump(1) << "\n"; });
  if (!o.plot.empty()) draw_plot(cstreams_plot_compare_script, out, o.plot);
}

}  // namespace

void add_compare_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand("compare",
                                 "Run the same scene on two or more devices: time per pass and step side by side, "
                                 "memory, and whether the contacts are identical (which differ, with each time)");
  cmd->add_option("--devices", o->devices, "Device filters, one per device (as --device elsewhere)")->required();
  add_measure_options(*cmd, *o);
  cmd->add_option("--json", o->json, "Write both measurements and every differing contact as JSON");
  cmd->add_option("--plot", o->plot, "Draw device time per pass and device as a PNG (python3-matplotlib)");
  cmd->callback([o, &command] {
    check(*o);
    if (o->devices.size() < 2) throw InputError("--devices: give at least two device filters to compare");
    if (!o->json.empty()) check_output_path("--json", o->json);
    if (!o->plot.empty()) check_output_path("--plot", o->plot);
    command = [o] { compare(*o); };
  });
}

}  // namespace cstreams::cli
