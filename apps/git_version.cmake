# Run at build time (cmake -P): writes OUT, a C++ file defining dicesim::git_describe() and
# dicesim::git_dirty(), from `git describe --always --dirty` in SRC. Only rewritten when the text
# changes, so an unchanged checkout rebuilds nothing. Outside a git checkout (a tarball) the version
# is the project's own (FALLBACK) and dirtiness is unknown (-1).
execute_process(COMMAND git -C "${SRC}" describe --always --dirty
                OUTPUT_VARIABLE describe RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(rc EQUAL 0 AND NOT describe STREQUAL "")
  if(describe MATCHES "-dirty$")
    set(dirty 1)
  else()
    set(dirty 0)
  endif()
else()
  set(describe "${FALLBACK}-nogit")
  set(dirty -1)
endif()
set(text "// Generated at build time by apps/git_version.cmake; never committed.
namespace dicesim {
const char* git_describe() { return \"${describe}\"; }
int git_dirty() { return ${dirty}; }
}  // namespace dicesim
")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
else()
  set(old "")
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUT}" "${text}")
endif()
