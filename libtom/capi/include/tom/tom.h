/* libtom's C API (C99): open a .tom file, read its meshes and scene, extract index buffers at
 * any resolution, and build .tom files from plain arrays. For engines in C or in any language
 * that binds a C ABI (Rust, C#, Zig, Odin, ...).
 *
 * Contracts that hold for every function:
 *  - No C++ type or exception crosses this header. A function that can fail returns a
 *    tom_status; TOM_OK is success. On failure tom_last_error() gives the library's one-line
 *    message (naming the file, the byte offset and the FORMAT.md rule for a bad .tom file) and
 *    the out-parameters are left as they were.
 *  - tom_last_error() is per thread: a failure on one thread never changes another's message.
 *  - Every pointer a tom_file hands out (views, streams, names, materials) stays valid until
 *    tom_file_close(); the file is read-only and may be used from several threads at once.
 *  - Extraction allocates nothing and writes only into the caller's buffer.
 *
 * The file format is specified in docs/FORMAT.md; the C++ API is tom/format.h and tom/extract.h.
 */
#ifndef TOM_TOM_H
#define TOM_TOM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TOM_C_API_VERSION 1

typedef enum tom_status {
    TOM_OK = 0,
    TOM_ERROR_FORMAT = 1,   /* a .tom file or buffer breaks docs/FORMAT.md */
    TOM_ERROR_IO = 2,       /* a file cannot be opened, mapped or written */
    TOM_ERROR_ARGUMENT = 3, /* a null pointer, an index out of range, a parameter out of its range */
    TOM_ERROR_MESH = 4,     /* a mesh handed to the builder cannot be used (index past its vertices, non-finite position) */
    TOM_ERROR_CAPACITY = 5, /* the caller's buffer is smaller than the result */
    TOM_ERROR_MEMORY = 6,   /* an allocation failed */
    TOM_ERROR_INTERNAL = 7, /* anything else; the message says what */
    TOM_ERROR_PARSE = 8     /* a text file does not parse (a libtcr calibration file, tom/tcr.h) */
} tom_status;

/* The message of this thread's last failure, or "" when there was none. Valid until this
 * thread's next failing call. */
const char* tom_last_error(void);
/* A constant name for a status: "TOM_OK", "TOM_ERROR_FORMAT", ... */
const char* tom_status_name(tom_status status);
/* The library's version, "MAJOR.MINOR.PATCH", and the newest .tom format version it reads. */
const char* tom_version(void);
uint32_t tom_format_version_major(void);
uint32_t tom_format_version_minor(void);

/* ---- files ---------------------------------------------------------------------------- */

typedef struct tom_file tom_file;

/* Maps `path` read-only and validates it against every rule of FORMAT.md (checksums included). */
tom_status tom_file_open(const char* path, tom_file** out);
/* Validates `size` bytes at `bytes` and uses them in place, without a copy: the caller keeps
 * them alive and unchanged until tom_file_close(). `name` (may be NULL: "<memory>") stands for
 * the path in messages. */
tom_status tom_file_open_memory(const void* bytes, size_t size, const char* name, tom_file** out);
/* Releases the file and everything it handed out. NULL is ignored. */
void tom_file_close(tom_file* file);

uint32_t tom_file_mesh_count(const tom_file* file);
/* What made the file (its PROV section: for tombuild's files a JSON object with the input's
 * digest, the files it read and the options; docs/FORMAT.md): `*bytes` (may be NULL) receives
 * its length; NULL when the file has none. The text is not terminated and lives as the file. */
const char* tom_file_provenance(const tom_file* file, size_t* bytes);

/* One mesh of a file: counts and pointers into its streams, in resolution order (vertex i is
 * the (i+1)-th to appear; the first n vertices are the mesh at resolution n). Optional streams
 * are NULL when absent. Filled by tom_file_mesh(); the extraction functions take it. */
typedef struct tom_mesh_view {
    const char* name; /* UTF-8, `name_length` bytes, not terminated */
    size_t name_length;
    uint32_t vertex_count;
    uint32_t triangle_count;
    uint32_t min_vertex_count; /* the coarsest resolution */
    uint32_t index_size;       /* bytes per stored index: 2 or 4 */
    int32_t material;          /* index into the file's materials, or -1 */
    uint32_t usable_floor;     /* the coarsest resolution the selections below pick: tombuild's
                                  stored usable floor (--floor-error), else min_vertex_count */
    const float* positions;  /* xyz per vertex */
    const float* normals;    /* xyz per vertex, or NULL */
    const float* texcoords;  /* uv per vertex (TEXCOORD_0), or NULL */
    const float* colors;     /* rgba per vertex, or NULL */
    const float* texcoords1; /* uv per vertex (TEXCOORD_1), or NULL */
    const float* tangents;   /* xyzw per vertex (w = +1 or -1), or NULL */
    const void* substitute;  /* index_size bytes per vertex: its substitute */
    const void* triangles;   /* index_size bytes * 3 per triangle, in death order */
    float bounds_min[3];
    float bounds_max[3];
    const void* internal; /* the library's view of this mesh: do not change */
} tom_mesh_view;

/* Fills `out` for mesh `index` (< tom_file_mesh_count). */
tom_status tom_file_mesh(const tom_file* file, uint32_t index, tom_mesh_view* out);

/* ---- resolutions and extraction ------------------------------------------------------- */

/* The resolution (vertex count) whose triangle count is the given fraction in [0, 1] of the
 * mesh's, or at least the given number of triangles, never below the usable floor (extract at an
 * explicit vertex count to go lower); and the triangles alive at a resolution.
 * A NULL or unfilled view gives 0. */
uint32_t tom_vertex_count_for_fraction(const tom_mesh_view* mesh, double fraction);
uint32_t tom_vertex_count_for_triangles(const tom_mesh_view* mesh, uint32_t triangle_count);
uint32_t tom_active_triangle_count(const tom_mesh_view* mesh, uint32_t vertex_count);

typedef struct tom_extracted {
    uint32_t vertex_count;   /* n: draw vertices [0, n) of the streams */
    uint32_t triangle_count; /* triangles written, 3 indices each */
} tom_extracted;

/* Writes the index buffer at resolution `vertex_count` (clamped to [min_vertex_count,
 * vertex_count]) into `out`, which holds `capacity` indices. 3 * triangle_count indices always
 * suffice; a smaller buffer that cannot hold the level gives TOM_ERROR_CAPACITY and writes
 * nothing useful. The u16 form needs a resolution of at most 65536 vertices. Allocates nothing. */
tom_status tom_extract_u32(const tom_mesh_view* mesh, uint32_t vertex_count, uint32_t* out, size_t capacity, tom_extracted* result);
tom_status tom_extract_u16(const tom_mesh_view* mesh, uint32_t vertex_count, uint16_t* out, size_t capacity, tom_extracted* result);

/* ---- parts --------------------------------------------------------------------------- */

/* A mesh drawn with several materials (a glTF mesh's primitives, an OBJ's usemtl groups) has
 * parts: ranges of its triangles sharing one vertex order. A mesh without them is one part. */
typedef struct tom_part {
    uint32_t first_triangle;
    uint32_t triangle_count;
    int32_t material;    /* index into the file's materials, or -1 */
    uint32_t attributes; /* the streams the part's source had: 1 normals, 2 TEXCOORD_0, 4 COLOR_0, 8 TEXCOORD_1, 16 tangents */
} tom_part;

/* The number of parts (1 for a mesh without parts; 0 for NULL), and part `index`. */
uint32_t tom_mesh_part_count(const tom_mesh_view* mesh);
tom_status tom_mesh_part(const tom_mesh_view* mesh, uint32_t index, tom_part* out);

/* One part's draw in a buffer written by tom_extract_parts_*: indices [first_index,
 * first_index + index_count) with `material`, over the vertices [0, n). */
typedef struct tom_part_draw {
    uint32_t first_index;
    uint32_t index_count;
    int32_t material;
    uint32_t reserved;
} tom_part_draw;

/* tom_extract_* that also says where each part's triangles went: `draws` holds
 * `draw_capacity` entries, at least tom_mesh_part_count(mesh) (else TOM_ERROR_CAPACITY). The
 * index buffer is the one tom_extract_* writes. Allocates nothing. */
tom_status tom_extract_parts_u32(const tom_mesh_view* mesh, uint32_t vertex_count, uint32_t* out, size_t capacity, tom_part_draw* draws,
                                 size_t draw_capacity, tom_extracted* result);
tom_status tom_extract_parts_u16(const tom_mesh_view* mesh, uint32_t vertex_count, uint16_t* out, size_t capacity, tom_part_draw* draws,
                                 size_t draw_capacity, tom_extracted* result);

/* Vertex n at the fractional resolution n + a (a in [0, 1]): a geomorph between n and n + 1
 * (tom::geomorph in tom/extract.h). Streams the mesh lacks are zero. */
typedef struct tom_morphed_vertex {
    uint32_t index;
    float position[3];
    float normal[3];
    float texcoord[2];
    float color[4];
    float texcoord1[2];
    float tangent[4];
} tom_morphed_vertex;
tom_status tom_geomorph(const tom_mesh_view* mesh, uint32_t n, float a, tom_morphed_vertex* out);

/* ---- the scene: materials and instances ----------------------------------------------- */

typedef enum tom_texture_role {
    TOM_TEXTURE_BASE_COLOR = 0,
    TOM_TEXTURE_METALLIC_ROUGHNESS = 1,
    TOM_TEXTURE_NORMAL = 2,
    TOM_TEXTURE_OCCLUSION = 3,
    TOM_TEXTURE_EMISSIVE = 4
} tom_texture_role;

typedef struct tom_texture {
    uint32_t role;      /* a tom_texture_role */
    uint32_t texcoord;  /* the TEXCOORD_n set it samples */
    const char* uri;    /* as written in the source asset, relative to it; "" for an embedded image */
    const char* mime_type; /* or "" */
} tom_texture;

typedef enum tom_alpha_mode { TOM_ALPHA_OPAQUE = 0, TOM_ALPHA_MASK = 1, TOM_ALPHA_BLEND = 2 } tom_alpha_mode;

typedef struct tom_material {
    const char* name; /* terminated, possibly "" */
    float base_color[4];
    float metallic;
    float roughness;
    float emissive[3];
    uint32_t alpha_mode; /* a tom_alpha_mode */
    float alpha_cutoff;
    int double_sided;
    const tom_texture* textures;
    uint32_t texture_count;
} tom_material;

typedef struct tom_instance {
    uint32_t mesh;      /* the mesh drawn */
    uint32_t node;      /* the source node */
    const char* name;   /* the node's name, terminated, possibly "" */
    float transform[16]; /* object to world, column-major */
} tom_instance;

uint32_t tom_file_material_count(const tom_file* file);
tom_status tom_file_material(const tom_file* file, uint32_t index, tom_material* out);
/* What to draw: the file's instances, or, when it stores none, every mesh once with the
 * identity transform (tom::draw_list). */
uint32_t tom_file_instance_count(const tom_file* file);
tom_status tom_file_instance(const tom_file* file, uint32_t index, tom_instance* out);

/* An image embedded in the source asset and stored in the file (format 1.6), byte for byte:
 * PNG, JPEG, WebP, KTX2, ... never decoded. */
typedef struct tom_image {
    const char* name;       /* the source's name for it, terminated, possibly "" */
    const char* mime_type;  /* "image/png", "image/jpeg", ..., terminated, never "" */
    const uint8_t* data;    /* `bytes` bytes in the file's mapping (no copy), valid until tom_file_close */
    uint64_t bytes;
} tom_image;

/* A glTF attribute carried unread (JOINTS_0, WEIGHTS_0, TEXCOORD_2, "_ID", ...) or a morph
 * target's deltas ("TARGET0/POSITION"): one element of `components` values of glTF component
 * type `component_type` per vertex, in resolution order, tightly packed (format 1.6, XATT). */
typedef struct tom_carried_stream {
    const char* name;        /* not terminated: name_bytes bytes */
    uint32_t name_bytes;
    uint32_t component_type; /* 5120 BYTE .. 5126 FLOAT, as glTF */
    uint32_t components;     /* 1 to 4 */
    uint32_t normalized;     /* 1: integers standing for [0, 1] or [-1, 1] */
    const void* data;        /* vertex_count elements, in the file's mapping */
} tom_carried_stream;

uint32_t tom_mesh_carried_stream_count(const tom_mesh_view* mesh);
tom_status tom_mesh_carried_stream(const tom_mesh_view* mesh, uint32_t index, tom_carried_stream* out);

uint32_t tom_file_image_count(const tom_file* file);
tom_status tom_file_image(const tom_file* file, uint32_t index, tom_image* out);
/* Which stored image texture `texture` of material `material` shows: *image is its index for
 * tom_file_image, or -1 when the image is a file named by the texture's uri. */
tom_status tom_file_texture_image(const tom_file* file, uint32_t material, uint32_t texture, int32_t* image);

/* ---- streamed files (tombuild --stream; docs/FORMAT.md, "Streamed files") ------------- */

/* A streamed .tom decodes as its bytes arrive: feed them in order, and any prefix that ends on a
 * chunk boundary is a valid file whose meshes stand at the resolutions received. Its chunks are
 * compressed with meshoptimizer's codecs; the library does not link meshoptimizer, so the caller
 * hands its two decoders in (one line each around meshopt_decodeVertexBuffer and
 * meshopt_decodeIndexBuffer, which return 0 on success as these must). `context` is passed to
 * both unchanged. */
typedef struct tom_stream_codecs {
    int (*decode_vertices)(void* context, void* out, size_t count, size_t size, const unsigned char* in, size_t in_bytes);
    int (*decode_indices)(void* context, uint32_t* out, size_t index_count, const unsigned char* in, size_t in_bytes);
    void* context;
} tom_stream_codecs;

typedef struct tom_stream tom_stream;

/* One chunk of a stream's directory, in file order: it adds vertices [vertex_begin, vertex_end)
 * to `mesh`, which then has `triangles` live triangles; a prefix of end_byte bytes decodes it. */
typedef struct tom_stream_chunk {
    uint32_t mesh, vertex_begin, vertex_end, triangles;
    uint64_t begin_byte, end_byte;
} tom_stream_chunk;

/* A decoder for one streamed file; `name` (may be NULL: "<stream>") stands for it in messages. */
tom_status tom_stream_create(const tom_stream_codecs* codecs, const char* name, tom_stream** out);
/* Takes the next `size` bytes and decodes every chunk they complete. On TOM_ERROR_FORMAT the
 * stream keeps what it decoded before and refuses further bytes (TOM_ERROR_ARGUMENT). */
tom_status tom_stream_append(tom_stream* stream, const void* bytes, size_t size);
/* The byte count up to which to fetch next: the header's end, the directory's, then the next
 * chunk's (or the deferred block's); the file's size when complete. */
uint64_t tom_stream_next_boundary(const tom_stream* stream);
uint64_t tom_stream_bytes_received(const tom_stream* stream);
uint64_t tom_stream_file_bytes(const tom_stream* stream); /* declared by the header; 0 before it */
int tom_stream_has_directory(const tom_stream* stream);
size_t tom_stream_chunk_count(const tom_stream* stream); /* 0 before the directory */
tom_status tom_stream_chunk_at(const tom_stream* stream, size_t index, tom_stream_chunk* out);
size_t tom_stream_decoded_chunks(const tom_stream* stream);
int tom_stream_complete(const tom_stream* stream); /* every chunk decoded, the deferred block in */
/* What is decoded, as a validated file of its own (every mesh at its decoded resolution, the
 * levels below it, the scene; the images once the deferred block is in), independent of the
 * stream: close it with tom_file_close. TOM_ERROR_FORMAT before the directory is in. */
tom_status tom_stream_snapshot(const tom_stream* stream, tom_file** out);
/* Releases the decoder (not the snapshots it made). NULL is ignored. */
void tom_stream_destroy(tom_stream* stream);

/* ---- building ------------------------------------------------------------------------- */

/* Memory the library hands to the caller (tom_build_memory's bytes). NULL functions mean
 * malloc and free. The library's working memory while it builds is its own. */
typedef struct tom_allocator {
    void* (*allocate)(void* user, size_t bytes);
    void (*release)(void* user, void* pointer);
    void* user;
} tom_allocator;

/* A mesh to build, from strided arrays. A stride of 0 means tightly packed. Optional streams
 * are NULL. Triangles are counter-clockwise. */
typedef struct tom_build_mesh {
    const char* name; /* may be NULL */
    uint32_t vertex_count;
    uint32_t triangle_count;
    const float* positions; size_t position_stride;   /* 3 floats per vertex */
    const float* normals; size_t normal_stride;       /* 3, or NULL: computed */
    const float* texcoords; size_t texcoord_stride;   /* 2 */
    const float* colors; size_t color_stride;         /* 4 */
    const float* texcoords1; size_t texcoord1_stride; /* 2 */
    const float* tangents; size_t tangent_stride;     /* 4 */
    const void* indices;   /* 3 per triangle */
    uint32_t index_size;   /* bytes per index: 2 or 4 */
    int32_t material;      /* -1 for none */
    /* Parts (several materials over one vertex array): `part_count` ranges that tile the
     * triangles in order, or NULL and 0 for a mesh of one part with `material`. */
    const tom_part* parts;
    uint32_t part_count;
} tom_build_mesh;

typedef enum tom_predicate { TOM_PREDICATE_QUADRIC = 0, TOM_PREDICATE_MEMORYLESS = 1 } tom_predicate;
typedef enum tom_strategy { TOM_STRATEGY_PASSES = 0, TOM_STRATEGY_HEAP = 1 } tom_strategy;

/* tombuild's options (docs/TOOLS.md); tom_build_params_default() gives its defaults. */
typedef struct tom_build_params {
    uint32_t predicate; /* a tom_predicate */
    uint32_t strategy;  /* a tom_strategy */
    float pair_threshold;
    float pass_fraction;
    float attribute_weight;
    float max_rotation_degrees;
    uint32_t threads;   /* 0: all cores; the output is the same for any count */
    int foresight;
    uint32_t index_size; /* stored index width: 0 automatic, 16 or 32 */
    int lock_borders;    /* non-zero: vertices on open borders are never removed (tombuild --lock-borders) */
    float animation_weight; /* weight of the skinning and morph-target terms (tombuild --animation-weight) */
    int weld;            /* non-zero (the default): identical vertices are merged first (0: tombuild --no-weld) */
    int keep_topology;   /* non-zero: no level joins two sheets; closed manifolds keep their genus (tombuild --keep-topology) */
} tom_build_params;

void tom_build_params_default(tom_build_params* params);

/* Builds `mesh_count` meshes into one .tom file image, allocated with `allocator` (NULL:
 * malloc); the caller owns *out_bytes and releases it with the allocator's release (or free).
 * `params` may be NULL (the defaults). Deterministic: the same input gives the same bytes. */
tom_status tom_build_memory(const tom_build_mesh* meshes, uint32_t mesh_count, const tom_build_params* params,
                            const tom_allocator* allocator, void** out_bytes, size_t* out_size);
/* The same, written to `path` atomically (a temporary renamed into place). */
tom_status tom_build_file(const tom_build_mesh* meshes, uint32_t mesh_count, const tom_build_params* params, const char* path);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* TOM_TOM_H */
