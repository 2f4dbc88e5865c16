#include "prepare/startup.h"

#include "core/progress.h"
#include "scene/work_bound.h"
#include "core/stage_clock.h"
#include "core/util.h"
#include "formats/assimp/model_window.h"
#include "formats/image/texture_file.h"
#include "dist/collective_cut.h"
#include "partition/pe_group.h"

namespace opsila {

std::string device_text(Ranks& ranks, int num_pes, const std::string& description) {
  if (ranks.size() <= 1) return description;
  const PeGroup g = pe_group(num_pes, ranks.size(), ranks.rank());
  return "rank " + std::to_string(g.rank) + " of " + std::to_string(g.ranks) + " (" + ranks.host() + "), PEs " +
         std::to_string(g.begin) + ".." + std::to_string(g.end - 1) + ": " + description;
}

SceneShare scene_share_for(Ranks& ranks) {
  SceneShare share;
  if (ranks.size() <= 1) return share;
  share.rank = ranks.rank(), share.ranks = ranks.size();
  share.combine = [&ranks](SceneShare& s) { combine_share(s, ranks); };  // a terrain's windows, added up
  share.decode_maps = decode_used_maps;  // texture images: only where the banks use them
  return share;
}

Scene load_view_scene(const std::string& path, const ViewOptions& view, bool quiet, OutputFiles& outputs,
                      const std::function<void(const std::string&)>& note, const SceneShare& share) {
  show_prepare_progress(!quiet);
  Scene scene = load_scene_or_explain(path, quiet, share);
  outputs.refuse_inputs(scene.input_files);
  apply_view_options(scene, view);
  if (!quiet)
    if (const std::string text = large_work_note(scene); !text.empty()) note(text);
  if (!quiet && share.ranks > 1 && is_streamed_model(path))
    if (const std::string why = model_stream_refusal(path); !why.empty())
      note(path + ": read whole by every rank (not as a stream in windows: " + why + ")");
  return scene;
}

}  // namespace opsila
