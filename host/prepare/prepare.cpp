#include "prepare/prepare.h"

#include "core/progress.h"
#include "dist/collective_cut.h"
#include "formats/assimp/model_window.h"
#include "formats/image/texture_file.h"
#include "partition/pe_group.h"
#include "prepare/prepare_banks.h"
#include "prepare/scene_limits.h"
#include "scene/work_bound.h"

namespace opsila {

namespace {


// The scene read (this rank's share when there are several), refused as an
// output, the view applied and checked; notes on a large frame or a model
// every rank reads whole.
Scene read_view_scene(const PrepareRequest& r, Ranks& ranks) {
  const SceneShare share = scene_share_for(ranks);
  const TriangleLimit limit = host_triangle_limit(ranks, r.view.host_memory);
  if (const std::string why = limit.no_room(); !why.empty()) throw InputError(why);
  show_prepare_progress(!r.quiet);
  Scene scene = load_scene_or_explain(r.view.scene_path, r.quiet, ranks, share, limit);
  if (r.outputs) r.outputs->refuse_inputs(scene.input_files);
  // Many small objects cost more than their triangles, and decoded maps
  // their texels (one process: a rank's share holds only its part of the
  // objects' clusters).
  if (share.ranks <= 1 && !r.reference) {
    std::uint64_t map_bytes = 0;
    for (const Texture& t : scene.textures) map_bytes += std::uint64_t(t.texels.size()) * sizeof(t.texels[0]);
    if (const std::string why = limit.objects_beyond(scene.total_triangles(), std::size_t(scene.num_objects), map_bytes);
        !why.empty())
      throw InputError(r.view.scene_path + why);
  }
  apply_view_options(scene, r.view);
  if (r.quiet || !r.note) return scene;
  if (const std::string text = large_work_note(scene); !text.empty()) r.note(text);
  const std::string& path = r.view.scene_path;
  if (share.ranks > 1 && is_streamed_model(path))
    if (const std::string why = model_stream_refusal(path); !why.empty())
      r.note(path + ": read whole by every rank (not as a stream in windows: " + why + ")");
  return scene;
}

}  // namespace

// Under several ranks each reads only its share of the scene and the ranks
// partition it together, with any --balance (docs/DISTRIBUTED.md). One
// process: the scene is whole.
SceneShare scene_share_for(Ranks& ranks) {
  SceneShare share;
  if (ranks.size() <= 1) return share;
  share.rank = ranks.rank(), share.ranks = ranks.size();
  share.combine = [&ranks](SceneShare& s) { combine_share(s, ranks); };  // a terrain's windows, added up
  share.decode_maps = decode_used_maps;  // texture images: only where the banks use them
  return share;
}

RenderSettings prepared_settings(const PrepareRequest& r) {
  ViewOptions machine = r.view;
  machine.balance = r.reference ? Balance::facets  // one processor, no banks to balance
                                : r.view.balance.value_or(r.balance);
  RenderSettings settings = render_settings(machine);
  settings.ranks = r.ranks;
  settings.progress = r.progress;
  settings.count_work = r.count_work;
  settings.launch_records = r.launch_records;
  settings.item_buffer_output = r.item_buffer_output;
  return settings;
}

PreparedScene prepare_scene(const PrepareRequest& r, ClRuntime* runtime) {
  OneProcess solo;  // one process when the request names no ranks
  Ranks& ranks = r.ranks ? *r.ranks : solo;
  PreparedScene p;
  p.settings = prepared_settings(r);
  p.settings.ranks = &ranks;
  p.scene = read_view_scene(r, ranks);
  if (runtime && !r.reference) {
    check_device_room(p.scene, r.view.scene_path, ranks, *runtime);
    p.banks = prepare_banks_consuming(p.scene, p.settings, *runtime);
  }
  p.settings.ranks = r.ranks;
  return p;
}

std::string device_text(Ranks& ranks, int num_pes, const std::string& description) {
  if (ranks.size() <= 1) return description;
  const PeGroup g = pe_group(num_pes, ranks.size(), ranks.rank());
  return "rank " + std::to_string(g.rank) + " of " + std::to_string(g.ranks) + " (" + ranks.host() + "), PEs " +
         std::to_string(g.begin) + ".." + std::to_string(g.end - 1) + ": " + description;
}

}  // namespace opsila
