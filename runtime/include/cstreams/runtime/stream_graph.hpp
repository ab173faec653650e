#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace cstreams::runtime {

struct StreamId {
  std::uint32_t index = 0xffffffffu;
  friend bool operator==(StreamId a, StreamId b) { return a.index == b.index; }
  friend bool operator!=(StreamId a, StreamId b) { return a.index != b.index; }
};
// Whether a graph has the stream: ids a graph leaves unset (a stream the scene does not
// need) are default-made.
inline bool has(StreamId s) { return s != StreamId{}; }
struct ParamId {
  std::uint32_t index = 0xffffffffu;
};

// A kernel by source file, function name and extra build options.
struct KernelRef {
  KernelRef(std::string program_file, std::string kernel_name, std::string build_options = {})
      : program(std::move(program_file)), kernel(std::move(kernel_name)), options(std::move(build_options))
  {
  }
  std::string program;
  std::string kernel;
  std::string options;
};

// The arguments a pass binds itself, in order; the scheduler appends its own after them.
struct BufferArg { StreamId stream; };  // the stream's buffer
struct CountArg { StreamId stream; };   // uint: the stream's item count at launch
struct ValueArg { std::vector<unsigned char> bytes; };
struct ParamArg { ParamId param; };     // the parameter's value at launch (Scheduler::set)
using PassArg = std::variant<BufferArg, CountArg, ValueArg, ParamArg>;

inline PassArg buffer_of(StreamId s) { return BufferArg{s}; }
inline PassArg count_of(StreamId s) { return CountArg{s}; }
inline PassArg param_of(ParamId p) { return ParamArg{p}; }
template <class T> PassArg value_of(const T& v)
{
  static_assert(std::is_trivially_copyable_v<T>);
  ValueArg a;
  a.bytes.resize(sizeof(T));
  std::memcpy(a.bytes.data(), &v, sizeof(T));
  return a;
}

// Work that refines itself round by round on the device, for a pass launched over a
// stream of inputs: each input's work is a list of items that a round turns into the
// next round's items, until a round leaves none. The scheduler launches, with the
// pass's own arguments first and then these:
//   seed   over the inputs:    __global S* state, __global I* list, __global uint* counts,
//          const uint capacity
//          calling cs_worklist_seed_begin first (runtime/worklist.h), then one first
//          item per input (list[i]) and the input's state (state[i]); it may add more
//          first items at cs_worklist_seed_index;
//   round  `round_items` work-items, each group striding over the round's items
//          (cl_kernels/runtime/worklist.h): __global S* state, __global const I* in,
//          __global I* out, __global uint* counts, const uint round, const uint capacity,
//          ending with cs_worklist_check_loops(counts, round);
//   then the pass's kernel over the inputs: __global S* state, then its emitters.
// Rounds go in batches with no host round trip between them; the host reads the
// counts once a batch. The pass's kernel runs behind the first batch before its counts
// are known (they come back with the stage's counters); where the rounds were not done,
// they go on and it runs again, so it must only read the state. A round that overflows
// the list stops the rounds after it; the lists grow, keeping its input, and it runs
// again as a replay (cs_worklist_replay), which must append the items it appended
// before and leave the state as one run of the round would: updates that are not
// idempotent (a count) are skipped there. A seed that overflows starts the work again.
// So no item is lost, and no round but the one that overflowed runs twice.
struct Worklist {
  std::string seed, round;       // kernel names in the pass's program
  std::size_t item_bytes = 0;    // I
  std::size_t state_bytes = 0;   // S, per input
  std::size_t round_items = 0;   // work-items a round launches
  // Work-items a group of a round launch and of the seed's, at most the context's (0:
  // the context's). Groups share nothing but an append, so kernels heavy in registers
  // can run in small groups, as many at once as the device's registers hold.
  std::size_t round_group = 0;
  // State that an optional mode of the rounds keeps: this many bytes per input more,
  // after the n inputs' states, held only while the 4-byte parameter `extra_state_while`
  // is nonzero, so that runs without the mode hold none of it.
  std::size_t extra_state_bytes = 0;
  ParamId extra_state_while{};
  // The most device memory the state and both lists may take for the pass's inputs
  // (0: what the device has): a run whose inputs need more goes in slices of them, as
  // where the device has no memory left (Scheduler), each slice refined in turn. Lists
  // still grow past it where a slice's rounds widen.
  std::size_t most_bytes = 0;
};

// One kernel over the items of a stream, and what it reads and writes.
//
// Kernel signature: the pass's own arguments, then per emitted stream (in emit order)
// CS_EMITTER_PARAMS(T, name), then for a culling pass `__global uint* keep` (one flag
// per item of the culled stream). A pass must not write what it reads: reruns after
// an overflow rely on passes being functions of their inputs. The exceptions are
// update(): a pass that neither emits nor culls (so it never reruns) may modify a
// fixed stream in place; several such passes apply in declaration order, after the
// stream's writer and before every pass that reads it (a BVH refit, level by level);
// and lower(): any pass may take a running minimum into a fixed stream, which running
// it again, or over slices of its input, leaves as one run would.
struct PassSpec {
  std::string name;
  KernelRef kernel{"", ""};
  StreamId over;                      // one work-item per item of this stream (and of
  std::vector<StreamId> also_over;    // these, after it, in order), or
  std::size_t items = 0;              // this many work-items when `over` is not set
  std::size_t group = 0;              // work_group(); 0: the context's
  std::vector<StreamId> reads;
  std::vector<StreamId> writes;       // fixed-length outputs
  std::vector<StreamId> emits;        // variable-length outputs, through registration
  std::vector<StreamId> updates;      // fixed-length streams modified in place
  std::vector<StreamId> lowers;       // fixed-length streams lowered to minimums in place
  StreamId cull_source, cull_target;  // compaction of cull_source into cull_target
  std::vector<std::pair<StreamId, StreamId>> handovers;  // (input, emitted stream): hand_over()
  std::vector<PassArg> args;
  double items_per_work_item = 2;     // expected emissions of each emitted stream, to size first segments
  std::vector<std::pair<StreamId, double>> emit_expectations;  // what emit(s, per_work_item) set instead
  std::optional<Worklist> worklist;
  StreamId stop_flag;                 // a fixed output: a nonzero first word stops the run
  bool any_order = false;             // emits_in_any_order()
  ParamId runs_while;                 // only_while(); unset: every run
  ParamId variant_while;              // instead_while(): the parameter, and
  std::string variant_kernel;         // the kernel launched while it is set

  PassSpec& launch_over(StreamId s) { over = s; return *this; }
  PassSpec& launch_over(std::vector<StreamId> streams)
  {
    over = streams.at(0);
    also_over.assign(streams.begin() + 1, streams.end());
    return *this;
  }
  PassSpec& launch_items(std::size_t n) { items = n; return *this; }
  // Launches in groups of at most `work_items` (the context's size where that is
  // smaller), and registers its emissions in segments of such groups. Groups that share
  // nothing but appends let a kernel heavy in registers fit more of them on a compute
  // unit; its kernel must not size or stride by CS_WG_SIZE, the program's group size.
  PassSpec& work_group(std::size_t work_items) { group = work_items; return *this; }
  bool launches_over_stream() const { return over.index != 0xffffffffu; }
  PassSpec& read(StreamId s) { reads.push_back(s); return *this; }
  PassSpec& write(StreamId s) { writes.push_back(s); return *this; }
  PassSpec& emit(StreamId s) { emits.push_back(s); return *this; }
  // Emits s, expecting about `per_work_item` items of it a work-item (rather than
  // expect_items()): what its segments hold before a run has planned them.
  PassSpec& emit(StreamId s, double per_work_item)
  {
    emit_expectations.emplace_back(s, per_work_item);
    return emit(s);
  }
  double expected_items(StreamId s) const
  {
    for (const auto& [stream, per_work_item] : emit_expectations)
      if (stream == s) return per_work_item;
    return items_per_work_item;
  }
  PassSpec& update(StreamId s) { updates.push_back(s); return *this; }
  // The pass lowers words of the fixed stream s to minimums of what they held and what
  // it finds (atomic_min), and so may emit, cull or run again: it runs after the
  // stream's writer and updates, and before every pass that reads s.
  PassSpec& lower(StreamId s) { lowers.push_back(s); return *this; }
  PassSpec& cull(StreamId source, StreamId target) { cull_source = source; cull_target = target; return *this; }
  PassSpec& arg(PassArg a) { args.push_back(std::move(a)); return *this; }
  PassSpec& expect_items(double per_work_item) { items_per_work_item = per_work_item; return *this; }
  PassSpec& refine(Worklist w) { worklist = std::move(w); return *this; }
  // The emitted stream `output` takes the buffer of `input`, a variable stream that only
  // this pass reads: its items are packed there once the stage's counters show that the
  // pass need not run again, and `input` is left empty (a BVTT front updated into the
  // buffer it was read from, so that the device holds one front, not two). A run refuses
  // to start while `input` is empty this way; upload to it or swap it first. Only the
  // segmented-lock registration hands over: the global counter writes into `output`
  // during the kernel, and lock-free segments share their offsets between emitters, so
  // under those `output` gets its own buffer.
  PassSpec& hand_over(StreamId input, StreamId output) { handovers.emplace_back(input, output); return *this; }
  // After the pass, the scheduler reads the first word of `flag` (a fixed stream the
  // pass writes) and throws RunStopped where it is not 0.
  PassSpec& stop_if(StreamId flag) { stop_flag = flag; return *this; }
  // No reader depends on the order of what the pass emits (a sort or a minimum follows):
  // it registers through each stream's global counter whatever the scheduler's
  // registration, which spares the segments' scan and merge. The order then varies
  // from run to run.
  PassSpec& emits_in_any_order() { any_order = true; return *this; }
  // The pass runs only while the 4-byte parameter `p` is not 0 (a result the host asks
  // for in some runs alone); otherwise it is skipped, and the fixed streams it writes or
  // updates keep what they held. Such a pass must not emit, cull or refine, whose
  // outputs later passes could not do without.
  PassSpec& only_while(ParamId p) { runs_while = p; return *this; }
  // While the 4-byte parameter `p` is not 0 the pass launches `kernel` instead, a kernel
  // of the same program, built with the same options, taking the same arguments: the
  // pass in an optional mode, whose work its own kernel then carries nothing of (a
  // kernel with both behind a branch takes the registers of both). Not for a pass that
  // refines a work list, whose kernels are its own.
  PassSpec& instead_while(ParamId p, std::string kernel)
  {
    variant_while = p;
    variant_kernel = std::move(kernel);
    return *this;
  }
  bool culls() const { return cull_source.index != 0xffffffffu; }
  bool stops() const { return stop_flag.index != 0xffffffffu; }
  bool conditional() const { return runs_while.index != 0xffffffffu; }
};

// Every stream a pass reads (declared reads, its launch stream, the culled stream and
// buffer arguments it does not write) and every stream it produces.
std::vector<StreamId> pass_inputs(const PassSpec& pass);
std::vector<StreamId> pass_outputs(const PassSpec& pass);

struct StreamSpec {
  std::string name;
  std::size_t element_bytes = 0;
  bool variable = false;
  std::size_t size = 0;  // item count (fixed) or initial capacity (variable)
  bool gathered = false; // StreamGraph::gather
  bool within_run = false; // StreamGraph::within_run
};

struct ParamSpec {
  std::string name;
  std::size_t bytes = 0;
};

// A declaration of streams and passes; the Scheduler orders and runs it. Nothing here
// touches a device, so a graph can be built, inspected and tested anywhere.
class StreamGraph {
public:
  StreamId fixed(std::string name, std::size_t element_bytes, std::size_t count);
  StreamId variable(std::string name, std::size_t element_bytes, std::size_t initial_capacity);
  ParamId param(std::string name, std::size_t bytes);
  // Marks a variable stream that the caller reads after a run (contacts, a front for the
  // next run). Short of memory, the scheduler may run a pass and those that depend on
  // it over slices of the pass's input, one slice after another (Scheduler::run); a
  // stream so marked then gathers the items of every slice, any other keeps only the
  // last slice's.
  void gather(StreamId stream);
  // Marks a variable stream that nothing reads once the passes of its run that read it
  // are done: not the caller, not the next run (triangle pairs, which only the
  // decomposition reads). In the step arena its place may then go back as soon as its
  // last reader has packed its first output, so that the outputs after it can take that
  // place joined to the first's segments; reading it after the run is an error.
  void within_run(StreamId stream);
  PassSpec& pass(std::string name, KernelRef kernel);

  const std::vector<StreamSpec>& streams() const { return streams_; }
  const std::vector<PassSpec>& passes() const { return passes_; }
  const std::vector<ParamSpec>& params() const { return params_; }
  const StreamSpec& stream(StreamId s) const;

  // Pass indices in an order where every stream is written (and updated) before it is
  // read; among passes free to go, declaration order. Throws naming the passes on a
  // cycle, a stream with two writers, a pass that writes what it reads, an update of a
  // variable stream or by a pass that emits or culls, two passes of one name, a
  // culling pass not launched over the stream it culls, or a work list without its
  // kernels, sizes or input stream.
  std::vector<std::size_t> schedule() const;

private:
  std::vector<StreamSpec> streams_;
  std::vector<PassSpec> passes_;
  std::vector<ParamSpec> params_;
};

}  // namespace cstreams::runtime
