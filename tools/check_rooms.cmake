cmake_policy(VERSION 3.20)  # IN_LIST, POP_FRONT
# Every #include of host/ against the rooms' table (host/rooms.cmake, the
# same table that links the rooms' libraries): a room's files include only
# its own room and the rooms it uses, directly or not. Run by ctest
# (RoomIncludes); fails naming the file and the include that breaks the rule.
#   cmake -DSRC=<source dir> -P tools/check_rooms.cmake
include(${SRC}/host/rooms.cmake)
# A room's closure: itself and every room it uses, directly or not.
function(opsila_room_closure room out)
  set(todo ${room})
  set(seen "")
  while(todo)
    list(POP_FRONT todo r)
    if(NOT r IN_LIST seen)
      list(APPEND seen ${r})
      list(APPEND todo ${OPSILA_ROOM_USES_${r}})
    endif()
  endwhile()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()
set(bad "")
# The table is a layering: a room uses only rooms listed before it (no cycle).
foreach(room ${OPSILA_ROOMS})
  list(FIND OPSILA_ROOMS ${room} here)
  foreach(use ${OPSILA_ROOM_USES_${room}})
    list(FIND OPSILA_ROOMS ${use} there)
    if(there EQUAL -1 OR NOT there LESS here)
      string(APPEND bad "  host/rooms.cmake: ${room} uses ${use}, which is not a room listed before it\n")
    endif()
  endforeach()
endforeach()
foreach(room ${OPSILA_ROOMS})
  opsila_room_closure(${room} allowed)
  file(GLOB files ${SRC}/host/${room}/*.h ${SRC}/host/${room}/*.cpp)
  # The executable's main (host/app/main.cpp) runs the bench command too.
  list(REMOVE_ITEM files ${SRC}/host/app/main.cpp)
  foreach(f ${files})
    file(STRINGS ${f} lines REGEX "^#include \"[a-z_]+/")
    foreach(line ${lines})
      # The room of an include: its folder ("formats/obj" for formats/obj/x.h).
      string(REGEX REPLACE "^#include \"(.*)/[a-z_]+\\.h\".*" "\\1" target "${line}")
      list(FIND allowed ${target} at)
      if(at EQUAL -1)
        file(RELATIVE_PATH rel ${SRC} ${f})
        string(APPEND bad "  ${rel}: ${line} (${room} may include: ${allowed})\n")
      endif()
    endforeach()
  endforeach()
endforeach()
# Every folder of host/ with sources is a room of the table.
file(GLOB_RECURSE sources RELATIVE ${SRC}/host ${SRC}/host/*.cpp ${SRC}/host/*.h)
foreach(s ${sources})
  get_filename_component(dir ${s} DIRECTORY)
  if(NOT dir IN_LIST OPSILA_ROOMS)
    string(APPEND bad "  host/${s}: in host/${dir}, which is not a room of host/rooms.cmake\n")
  endif()
endforeach()
# Inside frame/, only the renderer (renderer.cpp, its private frame.h and
# the frame_*.cpp stages) includes frame/renderer.h; the types other rooms
# need are in scene/render_types.h.
file(GLOB files ${SRC}/host/frame/*.h ${SRC}/host/frame/*.cpp)
foreach(f ${files})
  get_filename_component(name ${f} NAME)
  if(NOT name MATCHES "^(renderer\\.cpp|frame\\.h|frame_[a-z_]+\\.cpp)$")
    file(STRINGS ${f} lines REGEX "^#include \"frame/renderer\\.h\"")
    if(lines)
      string(APPEND bad "  host/frame/${name}: includes frame/renderer.h (use scene/render_types.h)\n")
    endif()
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "includes that break the rooms' rules:\n${bad}")
endif()
message(STATUS "every host/ include obeys its room's rule")
