# Inline the shared header and the kernel files (in the given order) into one
# C++ source defining opsila::NAME() (one OpenCL program's source). Local
# #include lines are dropped: the files are concatenated in dependency order
# instead.
string(REPLACE "|" ";" FILES "${FILES}")
set(text "")
foreach(f ${FILES})
  file(READ ${f} body)
  string(REGEX REPLACE "#include \"[^\"]*\"" "/* (inlined above) */" body "${body}")
  get_filename_component(name ${f} NAME)
  string(APPEND text "\n#line 1 \"${name}\"\n${body}")
endforeach()
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
