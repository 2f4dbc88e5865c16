#include "prepare/map_checks.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "formats/image/texture_file.h"

namespace opsila {

namespace {

// One check as bytes: the image's index, ok, width, height, the problem's
// length (five 64-bit words), then the problem. Records are self-delimiting,
// so the ranks' bytes can be gathered end to end.
void put_check(std::vector<unsigned char>& out, std::size_t k, const MapCheck& c) {
  const std::uint64_t head[5] = {k, c.ok ? 1u : 0u, std::uint64_t(c.width), std::uint64_t(c.height),
                                 c.problem.size()};
  const auto* bytes = reinterpret_cast<const unsigned char*>(head);
  out.insert(out.end(), bytes, bytes + sizeof head);
  out.insert(out.end(), c.problem.begin(), c.problem.end());
}

void take_checks(const std::vector<unsigned char>& all, std::vector<MapCheck>& checks) {
  for (std::size_t at = 0; at < all.size();) {
    std::uint64_t head[5];
    if (all.size() - at < sizeof head) throw std::logic_error("settle_maps: a truncated check");
    std::memcpy(head, all.data() + at, sizeof head);
    at += sizeof head;
    if (head[0] >= checks.size() || all.size() - at < head[4]) throw std::logic_error("settle_maps: a bad check");
    MapCheck& c = checks[std::size_t(head[0])];
    c.ok = head[1] != 0;
    c.width = static_cast<int>(head[2]), c.height = static_cast<int>(head[3]);
    c.problem.assign(all.begin() + std::ptrdiff_t(at), all.begin() + std::ptrdiff_t(at + head[4]));
    at += head[4];
  }
}

}  // namespace

void settle_maps(Scene& scene, Ranks& ranks) {
  ranks.checkpoint();  // a rank that failed reading is waiting there
  const std::vector<std::string> paths = maps_to_check(scene);
  std::vector<MapCheck> checks(paths.size());
  if (!scene.is_share()) {  // every rank holds the whole scene: every map, decoded here, as one process does
    for (std::size_t k = 0; k < paths.size(); ++k) checks[k] = check_texture_map(paths[k], true);
    settle_texture_maps(scene, checks);
    return;
  }
  std::vector<unsigned char> mine;
  for (std::size_t k = std::size_t(ranks.rank()); k < paths.size(); k += std::size_t(ranks.size()))
    put_check(mine, k, check_texture_map(paths[k]));
  take_checks(ranks.all_gather(mine), checks);
  settle_texture_maps(scene, checks);
}

}  // namespace opsila
