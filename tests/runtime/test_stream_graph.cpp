// A stream graph's declaration checked as it is scheduled (runtime/src/stream_graph.cpp).
#include "scheduler_graphs.hpp"

#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

using namespace cstreams::runtime;
using namespace cstreams::test;

TEST_CASE("invalid graphs are rejected with the names involved", "[runtime][scheduler][quick]")
{
  StreamGraph g;
  auto a = g.variable("a", 4, 1);
  auto b = g.variable("b", 4, 1);
  auto f = g.fixed("f", 4, 1);
  g.pass("p", {program, "k"}).launch_over(a).emit(b);
  g.pass("q", {program, "k"}).launch_over(b).emit(a);
  CHECK_THROWS_WITH(g.schedule(), Catch::Contains("cycle") && Catch::Contains("p") && Catch::Contains("q"));

  StreamGraph two;
  auto x = two.fixed("x", 4, 1);
  auto y = two.variable("y", 4, 1);
  two.pass("p", {program, "k"}).launch_over(x).emit(y);
  two.pass("q", {program, "k"}).launch_over(x).emit(y);
  CHECK_THROWS_WITH(two.schedule(), Catch::Contains("stream y is written by both p and q"));

  StreamGraph self;
  auto z = self.variable("z", 4, 1);
  self.pass("p", {program, "k"}).launch_over(z).emit(z);
  CHECK_THROWS_WITH(self.schedule(), Catch::Contains("both reads and writes stream z"));

  StreamGraph fixed_emit;
  auto u = fixed_emit.fixed("u", 4, 1);
  auto v = fixed_emit.fixed("v", 4, 1);
  fixed_emit.pass("p", {program, "k"}).launch_over(u).emit(v);
  CHECK_THROWS_WITH(fixed_emit.schedule(), Catch::Contains("emits into fixed-length stream v"));

  CHECK_THROWS_WITH(StreamGraph().fixed("odd", 6, 1), Catch::Contains("multiple of 4"));

  StreamGraph lives_on;
  const StreamId fixed = lives_on.fixed("fixed", 4, 1), kept = lives_on.variable("kept", 4, 1);
  CHECK_THROWS_WITH(lives_on.within_run(fixed), Catch::Contains("stream fixed is fixed-length"));
  lives_on.gather(kept);
  CHECK_THROWS_WITH(lives_on.within_run(kept), Catch::Contains("stream kept is gathered"));

  StreamGraph update_variable;
  auto w = update_variable.variable("w", 4, 1);
  update_variable.pass("p", {program, "k"}).launch_over(w).update(w);
  CHECK_THROWS_WITH(update_variable.schedule(), Catch::Contains("updates variable-length stream w"));

  StreamGraph update_and_emit;
  auto fx = update_and_emit.fixed("fx", 4, 1);
  auto out = update_and_emit.variable("out", 4, 1);
  update_and_emit.pass("p", {program, "k"}).launch_over(fx).update(fx).emit(out);
  CHECK_THROWS_WITH(update_and_emit.schedule(), Catch::Contains("may be rerun"));

  StreamGraph lower_variable;
  auto lv = lower_variable.variable("lv", 4, 1);
  lower_variable.pass("p", {program, "k"}).launch_items(4).lower(lv);
  CHECK_THROWS_WITH(lower_variable.schedule(), Catch::Contains("lowers variable-length stream lv"));

  StreamGraph wide_variant;
  auto wv = wide_variant.fixed("wv", 4, 1);
  wide_variant.pass("p", {program, "k"}).launch_over(wv).update(wv).instead_while(wide_variant.param("mode", 8), "k2");
  CHECK_THROWS_WITH(wide_variant.schedule(), Catch::Contains("pass p launches k2 while a parameter is set"));

  StreamGraph list_without_input;
  list_without_input.pass("p", {program, "k"}).launch_items(4).refine({"seed", "round", 8, 4, 64});
  CHECK_THROWS_WITH(list_without_input.schedule(), Catch::Contains("pass p refines a work list but lacks"));

  StreamGraph extra_behind_wide_param;
  auto inputs = extra_behind_wide_param.fixed("inputs", 4, 1);
  Worklist gated{"seed", "round", 8, 4, 64};
  gated.extra_state_bytes = 4;
  gated.extra_state_while = extra_behind_wide_param.param("mode", 8);
  extra_behind_wide_param.pass("p", {program, "k"}).launch_over(inputs).refine(gated);
  CHECK_THROWS_WITH(extra_behind_wide_param.schedule(), Catch::Contains("not behind a 4-byte parameter"));

  StreamGraph stop_unwritten;
  auto flag = stop_unwritten.fixed("flag", 4, 1);
  stop_unwritten.pass("p", {program, "k"}).launch_items(4).read(flag).stop_if(flag);
  CHECK_THROWS_WITH(stop_unwritten.schedule(), Catch::Contains("pass p stops the run on a flag it does not write"));
  (void)f;
}
