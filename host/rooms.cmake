# The rooms of host/ and what each may use (docs/ARCHITECTURE.md "The
# rooms"). One library per room: CMakeLists.txt links each to the rooms named
# here and nothing else, so a room that calls into a room it does not name
# fails to link (rooms are shared libraries linked with --no-undefined), and
# tools/check_rooms.cmake holds every #include to the same table.
# Order: a room names only rooms listed before it.
set(OPSILA_ROOMS
  core scene
  formats/common formats/image formats/obj formats/ply formats/stl formats/assimp formats/json
  device mpi partition frame dist reference prepare app bench)
set(OPSILA_ROOM_USES_core "")
set(OPSILA_ROOM_USES_scene core)
set(OPSILA_ROOM_USES_formats/common scene)
set(OPSILA_ROOM_USES_formats/image scene)
set(OPSILA_ROOM_USES_formats/obj formats/common formats/image)
set(OPSILA_ROOM_USES_formats/ply formats/common)
set(OPSILA_ROOM_USES_formats/stl formats/common)
set(OPSILA_ROOM_USES_formats/assimp formats/obj formats/ply formats/stl formats/image)
set(OPSILA_ROOM_USES_formats/json formats/assimp)
set(OPSILA_ROOM_USES_device scene)
set(OPSILA_ROOM_USES_mpi core)
set(OPSILA_ROOM_USES_partition scene)
set(OPSILA_ROOM_USES_frame device partition mpi)
set(OPSILA_ROOM_USES_dist frame)
set(OPSILA_ROOM_USES_reference scene)
set(OPSILA_ROOM_USES_prepare formats/json dist reference)
set(OPSILA_ROOM_USES_app prepare)
set(OPSILA_ROOM_USES_bench app)
