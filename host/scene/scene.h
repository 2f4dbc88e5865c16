// The scene as loaded: what docs/CONTRACT.md talks about (facets, objects, materials,
// camera, lights), before it is split into banks. Loaders fill it; the
// partitioner, the OpenCL renderer and the sequential reference read it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/vec.h"
#include "scene/triangle_limit.h"

namespace opsila {

// CONTRACT "Materials": an illumination model reflects (kr = Ks) for illum
// 3..7 and transmits (kt = Tf) for illum 4, 6 and 7.
bool illum_reflects(int illum);
bool illum_transmits(int illum);

// docs/CONTRACT.md "Materials", as read from MTL or a scene file.
struct MaterialDesc {
  std::string name;
  Vec3 ka{0, 0, 0}, kd{0, 0, 0}, ks{0, 0, 0}, tf{0, 0, 0};
  float ns = 1.0f, ni = 1.0f;
  int illum = 0;
  // CONTRACT "Texture maps": index into Scene::textures, -1 = no map (or the
  // image could not be read).
  int map_kd = -1, map_ka = -1;
  // The map files as an MTL file names them (options removed, not yet
  // looked up): the OBJ reader resolves and loads them.
  std::string map_kd_file, map_ka_file;
  // CONTRACT: kr = Ks when illum in {3..7}; kt = Tf when illum in {4,6,7}.
  Vec3 kr() const;
  Vec3 kt() const;
  static MaterialDesc default_material();  // the "face with no material" one
};

// CONTRACT "Materials": the Ka (Kd) of a material that leaves the key out:
// (1, 1, 1) when the material has a map_Ka (map_Kd), so that the texture
// alone gives the colour (glTF 1, IQM, SMD and MDL materials often carry
// only a texture), else 0. Every reader of materials (MTL, other model
// formats) fills left-out colours from here.
Vec3 left_out_colour(bool has_map);

// The one rule every reader (MTL, scene files, other model formats) applies
// to a material value: colours (Ka, Kd, Ks, Tf) and Ns must not be negative.
// So every term of CONTRACT's pixel sum is >= 0 (what the saturating pixel sums
// rely on) and pow(x, Ns) is never infinite. Returns "" or the problem,
// e.g. "must not be negative (-1)".
std::string material_value_problem(const std::string& key, float value);

// One triangle of a facet (polygons are fan-triangulated; all triangles of a
// polygon keep the polygon's facet id).
struct Triangle {
  Vec3 v0, v1, v2;
  int facet_id = 0;
  int object_id = 0;
  int material = 0;     // index into Scene::materials
  int attributes = -1;  // index into Scene::attributes, -1 = none
  int fan = 0;          // index in the facet's fan, 0 first: the hit order's last key (kernels/hit_order.h)
};

// What the vertices of one triangle carry besides their position (CONTRACT
// "barycentric attributes"): normals (OBJ vn) and texture coordinates (OBJ
// vt), in the triangle's vertex order. Kept apart from Triangle, since most
// scenes have neither.
struct VertexAttributes {
  std::array<Vec3, 3> normal{};
  std::array<std::array<float, 2>, 3> uv{};
  bool has_normals = false;
  bool has_uv = false;
};

// A decoded texture map: 8-bit sRGB texels packed as r | g << 8 | b << 16,
// row 0 = the top row of the image (CONTRACT's j = 0).
struct Texture {
  std::string path;  // as found on disk (or "file#name" for an embedded one)
  int width = 0, height = 0;
  std::vector<std::uint32_t> texels;
  // A scene read in shares: the image was checked, but its texels are
  // decoded only by the ranks whose facets use it (docs/DISTRIBUTED.md).
  bool pixels_later = false;
  // The file's device and inode (0, 0 for an embedded map): one file under
  // two names (a link, a second path) is one map, its texels held once.
  std::uint64_t file_device = 0, file_inode = 0;
  bool same_file(std::uint64_t device, std::uint64_t inode) const {
    return inode != 0 && file_inode == inode && file_device == device;
  }
};

// What a reader does with the image of each texture map its materials
// name: decodes it now, or only lists it (a scene read in shares,
// docs/DISTRIBUTED.md): its image is then checked once over the ranks
// after the read, and decoded only where used (formats/image/texture_file.h).
enum class MapImages { now, later };

// A texture map listed for its check after the read (MapImages::later):
// should the image fail, the warning one process gives (`where`, then that
// the map is ignored) goes before warnings[warning], or last when that is
// every warning.
struct MapRequest {
  std::string path;
  std::string where;
  std::size_t warning = 0;
};

// A model that a scene file places many times (scenes/FORMAT.md,
// "instances"): its triangles once, in its own frame. Facet ids are the
// model's own (0 .. num_facets - 1, in its order), object_id 0; materials
// and attributes index the scene's tables. Host/scene/instances.h places it.
struct Prototype {
  std::string name;  // what the scene file names (the model's file), for messages
  std::vector<Triangle> triangles;
  int num_facets = 0;
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};  // bounds in its frame
};

// One placement of a prototype: model to world x' = A x + b, and its
// inverse as the kernels apply it to rays (make_instance computes both),
// each row-major 3 x 4 (row i: A[i][0], A[i][1], A[i][2], b[i]).
struct InstanceDesc {
  int prototype = 0;
  std::array<double, 12> to_world{};
  std::array<float, 12> to_object{};
};

struct LightDesc {
  Vec3 position{0, 0, 0};
  Vec3 intensity{1, 1, 1};
};

struct CameraDesc {
  Vec3 eye{0, 0, 5}, look_at{0, 0, 0}, up{0, 1, 0};
  float fov_deg = 45.0f;
};

// A rank's share of a scene read by several MPI ranks (docs/DISTRIBUTED.md):
// Scene::triangles then holds only the objects dealt to this rank, and
// these figures describe the whole scene.
struct Scene;

// What the hit order (kernels/hit_order.h) needs of a scene's ids, checked
// by whoever builds a structure to search it (the banks, the reference
// tracer): material and fan indices that fit BankTriangle::material_fan
// (else InputError naming the limit), and facet ids that never decrease as
// object ids increase (else std::logic_error: every reader numbers them so).
void check_hit_order_ids(const Scene& scene);

// The same limits where a reader meets them, so that the error names the
// file, line or key (`where`): a scene's material count (the default
// included), and the triangles of one facet's fan over its mesh's
// placements. `where` ends in ": " ("FILE:LINE: KEY: ").
void check_material_count(std::size_t materials, const std::string& where);
void check_fan_triangles(long long triangles, const std::string& where);

struct SceneShare {
  int rank = 0, ranks = 1;         // ranks == 1: the scene is whole
  std::size_t total_triangles = 0;  // every rank's, together
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};    // bounds of every rank's triangles
  double read_seconds = 0;          // this rank's time to read its share
  // Objects made in windows (a terrain: each rank makes only its slice of
  // its triangles) whose triangles lie on several ranks, in id order; the
  // partition cuts them collectively (dist/collective_cut.h).
  std::vector<int> spread;
  // This rank's triangles of windowed objects: counted in total_triangles
  // and the bounds above until `combine` adds up every rank's.
  std::size_t window_triangles = 0;
  // Zero-area triangles each windowed entry dropped here, in entry order
  // (summed by `combine`, then warned about once).
  std::vector<std::uint64_t> window_dropped;
  // Set by whoever knows the ranks: sums window_triangles and joins the
  // bounds over every rank (a collective call, made by the reader once
  // every entry is built). Unset: the figures stay this rank's.
  std::function<void(SceneShare&)> combine;
  // What this rank read of each file it streamed (FileReadStamp::after),
  // in read order: `combine` refuses the scene, naming the file, unless
  // every rank's are the same (the file changed while the ranks read it,
  // or they see different copies of it), before anything is exchanged.
  std::vector<std::pair<std::string, std::vector<std::uint64_t>>> reads;
  // Set with it: decodes the texture maps the given facets use (their
  // images were checked while reading, formats/image/texture_file.h) and returns
  // the texel bytes held; the partition calls it on the facets a rank's
  // banks received. Unset: every map is decoded already.
  std::function<std::uint64_t(Scene&)> decode_maps;
  // What the readers do with the texture maps' images.
  MapImages map_images = MapImages::now;
  // A whole scene whose triangles went to the banks
  // (Scene::release_triangles): total_triangles and the bounds above are
  // its figures, as they are a share's.
  bool banked = false;
};

struct Scene {
  std::vector<Triangle> triangles;  // all of them, or this rank's share
  SceneShare share;
  std::vector<VertexAttributes> attributes;  // referenced by Triangle::attributes
  std::vector<MaterialDesc> materials;  // never empty after loading
  std::vector<Texture> textures;        // referenced by MaterialDesc::map_kd / map_ka
  std::vector<LightDesc> lights;
  // Models placed many times, and their placements: instance i is object
  // num_objects + i (after every object of the scene's own; num_objects
  // does not count them), its facets keep the model's facet ids.
  std::vector<Prototype> prototypes;
  std::vector<InstanceDesc> instances;
  CameraDesc camera;
  int width = 640, height = 480;
  int max_depth = 5;
  int spp = 1;  // samples per pixel, N = k*k (CONTRACT "Camera"); see spp_problem
  bool smooth = false;  // CONTRACT "Smooth shading": interpolated vertex normals
  Vec3 ambient{0.1f, 0.1f, 0.1f};
  Vec3 background{0.0f, 0.0f, 0.0f};
  int num_objects = 0;  // object ids are 0 .. num_objects-1
  int num_facets = 0;   // facet ids are 0 .. num_facets-1
  // What the loader set explicitly (so a bare .obj can frame itself).
  bool has_camera = false;
  // Where a scene file gave the camera and its up vector ("FILE:LINE: camera",
  // "FILE:LINE: camera.up"), for a basis that float cannot hold (check_camera).
  std::string camera_where, camera_up_where;
  bool has_lights = false;
  std::vector<std::string> warnings;  // printed once each by the CLI
  // MapImages::later: the maps whose warnings wait for their images' check,
  // in the order of their places in `warnings`.
  std::vector<MapRequest> map_requests;
  // Every file the scene was read from (scene file, OBJ, MTL, textures): a
  // loader that reads a file adds it here, so that no output can overwrite it.
  std::vector<std::string> input_files;

  // Axis-aligned bounds of all triangles (every rank's, for a share),
  // instances included.
  void bounds(Vec3& lo, Vec3& hi) const;
  // Those of `triangles` alone (empty: lo = +inf, hi = -inf).
  void own_bounds(Vec3& lo, Vec3& hi) const;
  bool is_share() const { return share.ranks > 1; }
  // Whether the scene is known by its figures (SceneShare) rather than its triangles.
  bool by_figures() const { return is_share() || share.banked; }
  // Triangles of the whole scene (every rank's, for a share).
  std::size_t total_triangles() const { return by_figures() ? share.total_triangles : triangles.size(); }
  // Whether a ray can hit anything: triangles of its own (any rank's) or
  // instances (every rank holds them all).
  bool has_facets() const { return total_triangles() > 0 || !instances.empty(); }
  // The count and the bounds kept as figures (SceneShare), so that the
  // frame's epsilon and the reports stay the same once the triangles go:
  // taken while the triangles are whole, before anything consumes them.
  void keep_figures();
  // Gives the triangles up once the banks hold copies of them (keeping the
  // figures first, if not yet kept); nothing reads them after.
  void release_triangles();
  // CONTRACT: epsilon = 1e-4 x the diagonal of the scene's bounding box.
  float epsilon() const;
  // Length of the bounding box diagonal (computed in double, so a scene too
  // big for float shows up as infinity rather than as a wrong number).
  double diagonal() const;
};

// `from`'s warnings after `into`'s, their map requests with them.
void append_warnings(Scene& into, Scene& from);
// `first` ahead of the scene's warnings, its map requests kept in their places.
void put_warnings_first(Scene& scene, std::vector<std::string> first);

// The diagonal of the box [lo, hi] in double, and CONTRACT's epsilon for it:
// one home for both, so that code that already holds the bounds (a scan of
// every facet) need not scan again.
double box_diagonal(const Vec3& lo, const Vec3& hi);
inline float epsilon_for(double diagonal) { return static_cast<float>(1e-4 * diagonal); }

// Samples per pixel (CONTRACT "Camera"): N = k*k with 1 <= N <= kMaxSpp. The
// bound (k <= 32) keeps every pixel's 64-bit fixed-point sum of N samples far
// from overflow and a render's cost (N times the rays of N = 1) sane.
constexpr int kMaxSpp = 1024;
// Empty when n is an accepted sample count, else the problem, for a message
// that names the flag or key ("must be a square: 1, 4, 9, ..., 1024").
std::string spp_problem(long long n);
// k for N = k*k (N accepted by spp_problem). The grid: scene/camera.h.
int spp_side(int n);

// A camera that sees the whole box [lo, hi]: looks at the box centre from +z
// with up = +y, at distance d = r / sin(min(fov_v, fov_h) / 2), where r is
// half the box diagonal (the bounding sphere touches the narrower side of the
// view). fov_deg is the vertical field of view; aspect = width / height.
CameraDesc frame_bounds(const Vec3& lo, const Vec3& hi, float fov_deg = 45.0f,
                        float aspect = 4.0f / 3.0f);

// Largest image (scenes/FORMAT.md "Limits"): per side, and in pixels. (The
// triangles a process may take: scene/triangle_limit.h.)
constexpr int kMaxImageSide = 16384;
constexpr long long kMaxImagePixels = 1LL << 26;

// Largest accepted bounding-box diagonal: far beyond any real scene, yet small
// enough that eye positions, distances and epsilon all stay finite in float.
constexpr double kMaxSceneExtent = 1e30;

// Throws InputError("<where>: ...") unless the scene has a facet (its own
// or an instance's) and its bounding-box diagonal is positive, at most
// kMaxSceneExtent, and gives a positive epsilon in float.
void check_scene_extent(const Scene& scene, const std::string& where);
// The same from the figures: triangle count and bounds.
void check_scene_extent(std::size_t triangles, const Vec3& lo, const Vec3& hi, const std::string& where);
// What is wrong with bounds too large for the renderer ("scene extent too
// large (...)"), or "" when they are not: a reader that grows its bounds an
// object at a time names the object that took them past the limit.
std::string scene_extent_beyond(const Vec3& lo, const Vec3& hi);

}  // namespace opsila
