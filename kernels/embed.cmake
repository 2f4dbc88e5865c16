# Inline one OpenCL program into a C++ source defining opsila::NAME().
# ROOTS lists the program's kernel files ("|"-separated); each file's local
# #include "..." lines (relative to that file) are followed depth-first and
# each file is inlined once, before the first file that includes it: the
# includes, not a list kept elsewhere, fix the order. The #include lines
# themselves are dropped (the file stands above, or was inlined already).
cmake_policy(VERSION 3.20)
string(REPLACE "|" ";" ROOTS "${ROOTS}")
set_property(GLOBAL PROPERTY opsila_seen "")
set_property(GLOBAL PROPERTY opsila_text "")

function(inline_file path)
  get_filename_component(path "${path}" REALPATH)
  if(NOT EXISTS "${path}")
    message(FATAL_ERROR "embed.cmake: ${path} (included by ${including}) does not exist")
  endif()
  get_property(seen GLOBAL PROPERTY opsila_seen)
  if("${path}" IN_LIST seen)
    return()
  endif()
  set_property(GLOBAL APPEND PROPERTY opsila_seen "${path}")
  file(READ "${path}" body)
  get_filename_component(dir "${path}" DIRECTORY)
  # Only an #include at the start of a line counts (not one named in a comment).
  string(REGEX MATCHALL "\n#include \"[^\"]*\"" includes "\n${body}")
  set(including "${path}")
  foreach(line ${includes})
    string(REGEX REPLACE "\n#include \"([^\"]*)\"" "\\1" name "${line}")
    inline_file("${dir}/${name}")
  endforeach()
  string(REGEX REPLACE "#include \"[^\"]*\"" "/* (inlined above) */" body "${body}")
  get_filename_component(name "${path}" NAME)
  set_property(GLOBAL APPEND_STRING PROPERTY opsila_text "\n#line 1 \"${name}\"\n${body}")
endfunction()

foreach(root ${ROOTS})
  set(including "the program ${NAME}")
  inline_file("${root}")
endforeach()
get_property(text GLOBAL PROPERTY opsila_text)

# Raw string literals have a length limit in some compilers: split in chunks.
set(out "// Generated from kernels/*.cl by kernels/embed.cmake. Do not edit.\n#include <string>\nnamespace opsila {\nconst std::string& ${NAME}() {\n  static const std::string s = std::string()")
string(LENGTH "${text}" len)
set(pos 0)
while(pos LESS len)
  string(SUBSTRING "${text}" ${pos} 8000 chunk)
  string(APPEND out "\n    + R\"OPSILA_CL(${chunk})OPSILA_CL\"")
  math(EXPR pos "${pos} + 8000")
endwhile()
string(APPEND out ";\n  return s;\n}\n}  // namespace opsila\n")
file(WRITE ${OUT} "${out}")
