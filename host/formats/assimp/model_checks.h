// What a model file promises, checked before the importer believes it: the
// importer's readers allocate what headers ask for, follow offsets without
// 64-bit range checks and recurse once per level of a node hierarchy, and
// some accept files that end early. Each check throws one
// InputError("FILE: ...") naming the element at fault.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

#include "formats/common/model_files.h"

namespace opsila {

// The deepest node hierarchy placed (levels below the root) and the most
// nodes in one model; deeper or larger graphs are refused, naming the depth
// or count, before the importer builds them.
constexpr int kMaxNodeDepth = 1024;
constexpr std::size_t kMaxNodes = std::size_t(1) << 20;
// The deepest nesting of XML elements or braces in other text formats
// (a node level takes a few).
constexpr long kMaxNesting = 4 * kMaxNodeDepth;

// The memory the importer may add while it reads `bytes` of model (a file
// and the buffers it names): 1 GiB or 64 times the bytes, whichever is
// larger, but at most three quarters of the machine's memory; or
// OPSILA_IMPORT_MEMORY bytes. The glTF checks hold their estimate of the
// import to it, and the import's watchdog its resident memory.
std::uint64_t import_memory_budget(std::uint64_t bytes);

// The checks of the format that `ext` names (with or without its dot), for
// the file `path` read through `files`. PLY's and STL's are their rooms'
// (ply::check_ply, stl::check_stl). Returns the bytes the importer will
// read: the file's, and for glTF those of its external buffers too.
std::uint64_t check_model_file_shape(ModelFiles& files, const std::string& path, const std::string& ext);

// OFF: the vertex and face counts fit the file; every vertex line holds its
// numbers and every face line a count of 1 to 9 and that many indices of
// vertices in the file (the importer would clamp, drop or misread them).
void check_off(const std::string& text, std::size_t file_bytes, const std::string& name);
// Other text formats: XML elements or braces nested at most kMaxNesting deep.
void check_nesting(const std::string& bytes, const std::string& name);
// FBX text: every embedded file (`Content` strings) base64, in whole groups
// of four, before the importer's decoder (which overruns its buffer on
// anything else) reads it.
void check_fbx_text(const std::string& bytes, const std::string& name);
// Binary FBX: every zlib-compressed array inflates to its count times its
// element's size (the importer would keep zeros for what a short stream
// lacks), naming the array and its byte offset.
void check_fbx_binary(const std::string& bytes, const std::string& name);
// MD5 meshes: numJoints the joints listed, each joint's parent an earlier
// joint or -1; in each mesh every vert, tri and weight index below its
// count, a vert's weights within the weights, a weight's joint within the
// joints, a tri's vertices within the vertices.
void check_md5_mesh(const std::string& text, const std::string& name);
// Faces indexing a vertex list, each index checked, naming its line
// (index_checks.cpp): ASE's *MESH_FACE corners below *MESH_NUMVERTEX;
// AC3D's surface references below their OBJECT's numvert, a surface's mat
// below the MATERIAL lines; text DirectX .x Mesh faces below the Mesh's
// vertex count.
void check_ase(const std::string& text, const std::string& name);
void check_ac3d(const std::string& text, const std::string& name);
void check_x_text(const std::string& text, const std::string& name);
// COLLADA: count attributes whole numbers of at most 32 bits, <p>
// indices below 2^31, no <skew> (collada_checks.cpp), naming the line.
void check_collada(const std::string& text, const std::string& name);
// glTF (text) and GLB: chunk lengths within the file; buffers, buffer views
// and accessors within one another, in 64-bit arithmetic; external buffers
// within the file limit and as long as declared; node graph a forest of at
// most kMaxNodes nodes and kMaxNodeDepth levels; what the meshes use within
// import_memory_budget; skins and animations left out of what the importer
// reads (gltf_still.h). Returns the bytes of the external buffers.
std::uint64_t check_gltf(ModelFiles& files, const std::string& bytes, const std::string& path);
// What a glTF 2 states that the importer would ignore or misread, refused
// naming the key (gltf_meanings.cpp): a version it has, extensions it
// requires that the importer reads, float VEC3 positions and normals,
// base colours of 4 numbers in [0, 1], texture transforms of numbers.
void check_gltf_meanings(const nlohmann::json& root, const std::string& path);
// glTF 2: a scene's nodes, a node's mesh, camera and skin, a material's
// textures, a texture's image and sampler, each the index of an entry
// (gltf_references.cpp), refused naming the key.
void check_gltf_references(const nlohmann::json& root, const std::string& path);

}  // namespace opsila
