#pragma once
// Writing TOM levels: one resolution as OBJ or PLY, so a level can be opened in MeshLab or
// Blender, or one or several as binary glTF with the file's scene.
// Part of tom::io.

#include <cstdint>
#include <string>
#include <vector>

#include "tom/extract.h"
#include "tom/scene.h"
#include "tom/view.h"

namespace tom {

/// One mesh at one resolution: vertices [0, vertex_count) of `mesh` and triangles whose
/// indices are all < vertex_count.
struct ExportPart {
    const MeshView* mesh = nullptr;
    uint32_t vertex_count = 0;
    std::vector<uint32_t> indices;
    /// Where each of the mesh's parts lies in `indices` (extract_parts); empty: all of them are
    /// one group with the mesh's material.
    std::vector<PartDraw> draws;
};

/// Writes the meshes into one file, one after another (indices offset accordingly), with every
/// attribute stream that all of them have. The format follows the extension: .obj (text; v, vt,
/// vn, colours as "v x y z r g b"; an `o` per mesh, a `usemtl` per part with a material, and
/// beside it a .mtl of the same stem with the materials: Kd, d, Ke and the texture maps, their
/// URIs rewritten relative to the output when `texture_dir` names the folder they are relative
/// to; an image stored in the file is written beside the OBJ as STEM.image-K.EXT) or .ply (binary little-endian, colours as uchar rgba, and with materials an int
/// `material_index` per face, -1 for none). Files are written to temporary names and renamed.
/// \throw IoError when the extension is unknown, a file cannot be written, or a mesh refers to a
/// material the scene does not store.
void export_meshes(const std::string& path, const std::vector<ExportPart>& parts, const Scene& scene = {}, const std::string& texture_dir = "");

/// One mesh of a .tom file at one or more resolutions, for export_glb().
struct GlbMesh {
    const MeshView* mesh = nullptr;
    std::vector<uint32_t> vertex_counts;  ///< resolutions, finest first
    /// Per resolution, a view of the same mesh with vertex streams of that level's own (positions,
    /// normals, texture coordinates, colours, tangents: tom::refit_view's), or empty / null for
    /// the mesh's: such a level gets those accessors of its own and shares the carried streams.
    std::vector<const MeshView*> level_views = {};
};

/// Writes a binary glTF 2.0 (.glb). Per input mesh and resolution a glTF mesh of one primitive
/// per part (those with triangles at that resolution, each with its material and the optional
/// streams its source had);
/// all levels of an input mesh share its vertex streams (POSITION, NORMAL, TEXCOORD_0/1, COLOR_0,
/// TANGENT: the levels are prefixes of one vertex array) with their own indices (16-bit when they
/// fit), but a level given streams of its own (GlbMesh::level_views) has its own POSITION,
/// NORMAL, TEXCOORD_0/1, COLOR_0 and TANGENT. One node per instance of `scene` (instances index
/// `meshes`), with its world transform; without instances, one untransformed node per mesh. With several resolutions, each node's
/// coarser levels are nodes of their own listed by its MSFT_lod extension (coarser in order).
/// The scene's materials are written with their factors and textures: images stored in the file
/// (embedded in the source) are embedded in the output's binary buffer, byte for byte; images
/// that were files keep their URIs (`texture_dir`: the folder those are relative to, i.e. the
/// source asset's; they are rewritten relative to the output; empty keeps them as stored), or
/// with `embed_images` are read from there and embedded too. A WebP, KTX2 or AVIF image is shown
/// through EXT_texture_webp, KHR_texture_basisu or EXT_texture_avif (used and required).
/// With `compress` (tomextract -c), gltfpack -c's form: the vertex streams quantized
/// (KHR_mesh_quantization: positions on a 14-bit grid whose dequantization the nodes carry,
/// except a skinned or morphed mesh's; normals and tangents in bytes; texture coordinates in
/// [0, 1] in 16 bits; colours in bytes) and the vertex and index views encoded with
/// EXT_meshopt_compression (both required); vertices and triangles are reordered for the
/// encoders, the triangles and their data unchanged.
/// Written to a temporary name and renamed. \throw IoError when it cannot be written, when an
/// image to embed cannot be read, or when a mesh refers to a material the scene does not store.
void export_glb(const std::string& path, const std::vector<GlbMesh>& meshes, const Scene& scene = {}, const std::string& texture_dir = "",
                bool embed_images = false, bool compress = false);

} // namespace tom
