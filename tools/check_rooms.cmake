# The rule of each room of host/ (docs/ARCHITECTURE.md): which other rooms
# its files may include. Run by ctest (RoomIncludes); fails naming the file
# and the include that breaks the rule.
#   cmake -DSRC=<source dir> -P tools/check_rooms.cmake
set(allowed_core core)
set(allowed_input core input)
set(allowed_machine core machine)
set(allowed_reference core reference)
set(allowed_bench core input machine reference bench cli)
set(allowed_cli core input machine reference bench cli)
set(bad "")
foreach(room core input machine reference bench cli)
  file(GLOB files ${SRC}/host/${room}/*.h ${SRC}/host/${room}/*.cpp)
  foreach(f ${files})
    file(STRINGS ${f} lines REGEX "^#include \"[a-z_]+/")
    foreach(line ${lines})
      string(REGEX REPLACE "^#include \"([a-z_]+)/.*" "\\1" target "${line}")
      list(FIND allowed_${room} ${target} at)
      if(at EQUAL -1)
        file(RELATIVE_PATH rel ${SRC} ${f})
        string(APPEND bad "  ${rel}: ${line} (${room} may include: ${allowed_${room}})\n")
      endif()
    endforeach()
  endforeach()
endforeach()
# Below the renderer nothing includes it: the types other rooms need are in
# machine/render_types.h. Only the renderer itself (renderer.cpp, its
# private frame.h and frame_*.cpp stages) and the pilot frames (which run
# renderers) include machine/renderer.h inside the machine room.
file(GLOB files ${SRC}/host/machine/*.h ${SRC}/host/machine/*.cpp)
foreach(f ${files})
  get_filename_component(name ${f} NAME)
  if(NOT name MATCHES "^(renderer\\.cpp|pilot\\.cpp|frame\\.h|frame_[a-z_]+\\.cpp)$")
    file(STRINGS ${f} lines REGEX "^#include \"machine/renderer\\.h\"")
    if(lines)
      string(APPEND bad "  host/machine/${name}: includes machine/renderer.h (below the renderer: use machine/render_types.h)\n")
    endif()
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "includes that break the rooms' rules:\n${bad}")
endif()
message(STATUS "every host/ include obeys its room's rule")
