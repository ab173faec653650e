#pragma once
// What one fuzz input must do, shared by the libFuzzer targets (tests/fuzz/*.cpp) and
// the regression tests that replay their corpora in every build: parse, or be refused
// with InputError (the command line: or CLI11's ParseError). Any other exception, a
// crash or a sanitizer report is a finding; a broken invariant of a parsed result
// throws std::logic_error, which nothing here catches.
#include <string>
#include <string_view>

namespace cstreams::fuzz {

void mesh_readers(std::string_view bytes);
// `folder` holds the mesh files the manifest may name (tests/fuzz/meshes).
void scene_manifest(std::string_view bytes, const std::string& folder);
void query_csv(std::string_view bytes);
// Arguments separated by NUL or newline bytes; parsed, never run.
void command_line(std::string_view bytes);

}  // namespace cstreams::fuzz
