#include "scratch.hpp"

#include <cstreams/runtime/context.hpp>

#include <algorithm>

namespace cstreams::runtime {

bool Scratch::fits_once_gone(std::size_t gone, std::size_t bytes) const
{
  const std::size_t in_use = context_.memory_in_use() - std::min(gone, context_.memory_in_use());
  return !pressed_ && in_use + bytes <= context_.memory_limit();
}

void Scratch::take_segments(EmitterState& e, std::size_t bytes)
{
  if (use_arena_) {
    e.items = arena_.take(bytes, "registration segments", e.arena_at);
    return;
  }
  const std::size_t limit = context_.memory_limit(), room = limit - std::min(limit, context_.memory_in_use());
  if (auto idle = pool_.take(bytes, room)) {
    e.items = std::move(*idle);
    return;
  }
  with_memory([&] { e.items = Buffer(context_, std::max<std::size_t>(bytes, 1), "registration segments"); });
}

void Scratch::give_back_segments(EmitterState& e)
{
  if (e.arena_at != StepArena::none) drop_segments(e);
  else if (e.items) pool_.give_back(std::move(e.items));
}

void Scratch::drop_segments(EmitterState& e)
{
  arena_.give_back(e.arena_at);
  e.items = Buffer();
  drop_stage_scratch(e.counts, e.counts_at);
}

void Scratch::take_stage_scratch(Buffer& buffer, std::size_t& at, std::size_t bytes, const char* label)
{
  if (!use_arena_) {
    drop_stage_scratch(buffer, at);
    with_memory([&] { ensure_capacity(context_, buffer, bytes, label); });
    return;
  }
  if (at != StepArena::none && buffer.bytes() >= bytes) return;
  arena_.give_back(at);
  buffer = Buffer();
  with_memory([&] { buffer = arena_.take(bytes, label, at); });
}

void Scratch::drop_stage_scratch(Buffer& buffer, std::size_t& at)
{
  if (at == StepArena::none) return;
  arena_.give_back(at);
  buffer = Buffer();
}

void Scratch::drop_list(ListState& l)
{
  if (l.state_at == StepArena::none && l.lists_at[0] == StepArena::none && l.lists_at[1] == StepArena::none) return;
  drop_stage_scratch(l.state, l.state_at);
  for (int k = 0; k < 2; ++k) drop_stage_scratch(l.lists[k], l.lists_at[k]);
  l.released = std::max(l.released, l.needed > 0 ? std::min(l.needed, l.capacity) : l.capacity);
  l.capacity = 0;
}

void Scratch::stage_done(const std::vector<PassState*>& stage)
{
  std::vector<std::size_t> needs;
  for (PassState* p : stage) {
    for (auto& e : p->emitters)
      if (e.items) {
        needs.push_back(e.needed);
        give_back_segments(e);
      }
    drop_stage_scratch(p->keep, p->keep_at);
    if (p->list) drop_list(*p->list);
  }
  pool_.stage_done(std::move(needs));
}

bool Scratch::release_idle()
{
  bool freed = false;
  pressed_ = true;
  if (pool_.release()) freed = true;
  for (auto& other : passes_)
    if (std::find(busy_.begin(), busy_.end(), &other) == busy_.end()) release_pass(other, freed);
  if (arena_.release()) freed = true;
  return freed;
}

void Scratch::release_pass(PassState& p, bool& freed)
{
  const auto release = [&](Buffer& b) {
    if (b) {
      b = Buffer();
      freed = true;
    }
  };
  for (auto& e : p.emitters) {
    if (e.items || e.counts) freed = true;
    drop_segments(e);
    release(e.counts);
  }
  if (p.keep) freed = true;
  drop_stage_scratch(p.keep, p.keep_at);
  release(p.keep);
  // What a pass yet to run this run will emit holds the last run's items, which
  // nothing reads before it; it comes back at its size when the pass runs.
  if (running_ && !p.ran)
    for (StreamId s : p.spec->emits) {
      auto& st = streams_.state(s);
      if (!st.buffer) continue;
      st.released = std::max(st.released, st.capacity);
      streams_.drop(st);
      freed = true;
    }
  if (auto& l = p.list) {
    drop_list(*l);
    release(l->state);
    for (auto& list : l->lists) release(list);
    l->released = std::max(l->released, l->capacity);
    l->capacity = 0;
  }
}

void Scratch::start_run()
{
  pool_.start_run();
  if (pressed_) use_arena_ = false;
  for (auto& p : passes_) {
    for (auto& e : p.emitters)
      if (e.arena_at != StepArena::none || e.counts_at != StepArena::none) drop_segments(e);
    drop_stage_scratch(p.keep, p.keep_at);
    if (p.list) drop_list(*p.list);
  }
  for (auto& st : streams_.all())
    if (st.arena_at != StepArena::none || (use_arena_ && st.transient && st.buffer)) {
      st.released = std::max(st.released, st.capacity);
      streams_.drop(st);
    }
  if (use_arena_) arena_.start_run();
  else arena_.release();
  late_ = use_arena_ && (context_.memory_limit() >= context_.device().global_memory || arena_.bytes() > 0);
}

}  // namespace cstreams::runtime
