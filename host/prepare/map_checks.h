// The texture maps of a scene read under several MPI ranks, decided once
// for every rank (formats/image/texture_file.h, docs/DISTRIBUTED.md).
#pragma once

#include "scene/scene.h"
#include "mpi/ranks.h"

namespace opsila {

// After every rank has read its share: each image the scene names is
// checked by one rank (the k-th by rank k mod R) and what it found is
// gathered to every rank, so that the warnings, the maps ignored and the
// texture table are those of one process, whatever the rank count. The
// texels wait for the ranks whose banks use them (bank_share). A scene
// read whole (a bare model file) checks and decodes every map here.
void settle_maps(Scene& scene, Ranks& ranks);

}  // namespace opsila
