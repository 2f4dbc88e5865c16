# A two-room house whose lower room includes the upper one: the rooms'
# check (tools/check_rooms.cmake) must refuse it (ctest RoomIncludesRefuseABreak).
set(OPSILA_ROOMS core scene)
set(OPSILA_ROOM_USES_core "")
set(OPSILA_ROOM_USES_scene core)
