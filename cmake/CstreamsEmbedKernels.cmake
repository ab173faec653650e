# Embeds OpenCL C sources into a C++ translation unit at build time.
#
# cstreams_embed_kernels(<target> FUNCTION <name> BASE_DIR <dir> [HEADER <h>] FILES <file>...)
# adds to <target> a generated source that defines
#   const cstreams::runtime::SourceSet& <name>();
# (<name> may be namespace-qualified when HEADER, included first, declares it)
# returning every file verbatim under its path relative to BASE_DIR. The program
# registry expands #include "..." between embedded files and emits #line markers,
# so a build log names the real file and line.
set(_CSTREAMS_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_kernels.cmake)

function(cstreams_embed_kernels target)
  cmake_parse_arguments(ARG "" "FUNCTION;BASE_DIR;HEADER" "FILES" ${ARGN})
  string(MAKE_C_IDENTIFIER "${ARG_FUNCTION}" file_stem)
  set(out ${CMAKE_CURRENT_BINARY_DIR}/${file_stem}.cpp)
  set(names)
  foreach(f IN LISTS ARG_FILES)
    file(RELATIVE_PATH rel ${ARG_BASE_DIR} ${f})
    list(APPEND names ${rel})
  endforeach()
  add_custom_command(OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DFUNCTION=${ARG_FUNCTION} -DBASE_DIR=${ARG_BASE_DIR} -DHEADER=${ARG_HEADER}
            "-DNAMES=${names}" -P ${_CSTREAMS_EMBED_SCRIPT}
    DEPENDS ${ARG_FILES} ${_CSTREAMS_EMBED_SCRIPT}
    COMMENT "Embedding OpenCL sources into ${ARG_FUNCTION}"
    VERBATIM)
  target_sources(${target} PRIVATE ${out})
endfunction()
