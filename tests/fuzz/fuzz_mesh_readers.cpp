// libFuzzer target for the PLY and OBJ readers: any input must either parse into a
// valid mesh or raise InputError; nothing else (crash, hang, other exception) is allowed.
// Build: cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCSTREAMS_BUILD_FUZZERS=ON
// Run:   build-fuzz/bin/fuzz_mesh_readers tests/fuzz/corpus -max_total_time=60
#include <cstreams/io/mesh_io.hpp>

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // Either reader on every input: OBJ text is a malformed PLY and the reverse.
  for (bool ply : {true, false}) {
    try {
      const cstreams::Mesh m = ply ? cstreams::parse_ply(bytes, "fuzz.ply") : cstreams::parse_obj(bytes, "fuzz.obj");
      for (const auto& f : m.faces)
        for (auto v : f)
          if (v >= m.positions.size()) std::abort();
    } catch (const cstreams::InputError&) {
    }
  }
  return 0;
}
