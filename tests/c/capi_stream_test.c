/* The C API's stream decoder (tom/tom.h, "streamed files"), compiled as C99 with -Wall -Wextra
 * -pedantic -Werror and given libmeshoptimizer's decoders as an engine would: a streamed file
 * fed up to each next boundary decodes, chunk after chunk, to the ordinary file's level at the
 * chunk's vertex count, index for index; a textured asset's image arrives in its deferred block,
 * after the first chunk; a corrupted byte is a format error naming the file, after which the
 * decoder keeps what it decoded and takes nothing more.
 * Usage: capi_stream_test STREAM.tom ORDINARY.tom [TEXTURED-STREAM.tom] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <meshoptimizer.h>

#include "tom/tom.h"

#include "check.h"

/* The codecs: meshoptimizer's decoders, counting their calls through the context. */
static int decode_vertices(void* context, void* out, size_t count, size_t size, const unsigned char* in, size_t in_bytes) {
    ++*(size_t*)context;
    return meshopt_decodeVertexBuffer(out, count, size, in, in_bytes);
}
static int decode_indices(void* context, uint32_t* out, size_t index_count, const unsigned char* in, size_t in_bytes) {
    ++*(size_t*)context;
    return meshopt_decodeIndexBuffer(out, index_count, sizeof(uint32_t), in, in_bytes);
}

static unsigned char* read_all(const char* path, size_t* size) {
    FILE* f = fopen(path, "rb");
    unsigned char* bytes = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0) {
        bytes = (unsigned char*)malloc((size_t)n);
        if (bytes && fread(bytes, 1, (size_t)n, f) != (size_t)n) {
            free(bytes);
            bytes = NULL;
        }
        *size = (size_t)n;
    }
    fclose(f);
    return bytes;
}

/* Mesh 0 of `file` extracted at `vertices` (its whole index buffer, malloc'ed; NULL on failure). */
static uint32_t* level(const tom_file* file, uint32_t vertices, tom_extracted* result) {
    tom_mesh_view mesh;
    uint32_t* indices;
    if (tom_file_mesh(file, 0, &mesh) != TOM_OK) return NULL;
    indices = (uint32_t*)malloc(3 * (size_t)mesh.triangle_count * sizeof(uint32_t) + 4);
    if (indices && tom_extract_u32(&mesh, vertices, indices, 3 * (size_t)mesh.triangle_count, result) != TOM_OK) {
        free(indices);
        return NULL;
    }
    return indices;
}

/* Feeds the stream up to each next boundary; after each chunk, its snapshot against the
 * ordinary file's level there. Returns the decoder (complete). */
static tom_stream* check_every_chunk(const unsigned char* bytes, size_t size, const tom_file* ordinary, size_t* calls) {
    tom_stream_codecs codecs;
    tom_stream* stream = NULL;
    size_t fed = 0, chunks_seen = 0;
    codecs.decode_vertices = decode_vertices, codecs.decode_indices = decode_indices, codecs.context = calls;
    CHECK(tom_stream_create(&codecs, "bunny.tom", &stream) == TOM_OK);
    if (!stream) return NULL;
    CHECK(tom_stream_next_boundary(stream) == 64); /* the header first */
    while (fed < size) {
        const uint64_t next = tom_stream_next_boundary(stream);
        const size_t before = tom_stream_decoded_chunks(stream);
        if (next <= fed || next > size) break;
        CHECK(tom_stream_append(stream, bytes + fed, (size_t)(next - fed)) == TOM_OK);
        fed = (size_t)next;
        if (tom_stream_decoded_chunks(stream) > before) {
            tom_stream_chunk chunk;
            tom_file* prefix = NULL;
            tom_extracted got, expected;
            uint32_t *a, *b;
            CHECK(tom_stream_chunk_at(stream, before, &chunk) == TOM_OK);
            CHECK(chunk.end_byte == next);
            CHECK(tom_stream_snapshot(stream, &prefix) == TOM_OK);
            if (!prefix) continue;
            a = level(prefix, chunk.vertex_end, &got);
            b = level(ordinary, chunk.vertex_end, &expected);
            CHECK(a && b && got.triangle_count == chunk.triangles && expected.triangle_count == chunk.triangles);
            if (a && b) CHECK(memcmp(a, b, 3 * (size_t)got.triangle_count * sizeof(uint32_t)) == 0);
            free(a), free(b);
            tom_file_close(prefix); /* the snapshot is the caller's; the stream goes on */
            ++chunks_seen;
        }
    }
    CHECK(fed == size);
    CHECK(tom_stream_complete(stream));
    CHECK(chunks_seen == tom_stream_chunk_count(stream) && chunks_seen >= 10);
    CHECK(*calls >= chunks_seen); /* a chunk's attributes block (positions and normals), through the context */
    return stream;
}

int main(int argc, char** argv) {
    size_t size = 0, calls = 0;
    unsigned char* bytes;
    tom_file* ordinary = NULL;
    tom_stream* stream;
    if (argc < 3) {
        fprintf(stderr, "usage: capi_stream_test STREAM.tom ORDINARY.tom [TEXTURED-STREAM.tom]\n");
        return 2;
    }
    bytes = read_all(argv[1], &size);
    CHECK(bytes != NULL);
    CHECK(tom_file_open(argv[2], &ordinary) == TOM_OK);
    if (!bytes || !ordinary) return 1;

    stream = check_every_chunk(bytes, size, ordinary, &calls);
    if (stream) {
        tom_stream_chunk chunk;
        CHECK(tom_stream_chunk_at(stream, tom_stream_chunk_count(stream), &chunk) == TOM_ERROR_ARGUMENT);
        CHECK(strstr(tom_last_error(), "tom_stream_chunk_at") != NULL);
    }
    tom_stream_destroy(stream);

    { /* a flipped byte in the middle: an error naming the file and the checksum; what was decoded stays */
        tom_stream_codecs codecs;
        tom_stream* bad = NULL;
        tom_file* kept = NULL;
        codecs.decode_vertices = decode_vertices, codecs.decode_indices = decode_indices, codecs.context = &calls;
        bytes[size / 2] ^= 0x40;
        CHECK(tom_stream_create(&codecs, "flipped.tom", &bad) == TOM_OK);
        CHECK(tom_stream_append(bad, bytes, size) == TOM_ERROR_FORMAT);
        CHECK(strstr(tom_last_error(), "flipped.tom") != NULL && strstr(tom_last_error(), "checksum") != NULL);
        CHECK(tom_stream_decoded_chunks(bad) > 0 && !tom_stream_complete(bad));
        CHECK(tom_stream_append(bad, bytes, 1) == TOM_ERROR_ARGUMENT);
        CHECK(tom_stream_snapshot(bad, &kept) == TOM_OK);
        CHECK(kept && tom_file_mesh_count(kept) == 1);
        tom_file_close(kept);
        tom_stream_destroy(bad);
    }
    { /* the ordinary reader refuses a stream and names what decodes it */
        tom_file* wrong = NULL;
        CHECK(tom_file_open(argv[1], &wrong) == TOM_ERROR_FORMAT && wrong == NULL);
        CHECK(strstr(tom_last_error(), "a streamed .tom") != NULL && strstr(tom_last_error(), "tom_stream_create") != NULL);
    }
    { /* the argument checks */
        tom_stream_codecs none;
        tom_stream* s = NULL;
        memset(&none, 0, sizeof none);
        CHECK(tom_stream_create(&none, NULL, &s) == TOM_ERROR_ARGUMENT && s == NULL);
        CHECK(tom_stream_create(NULL, NULL, &s) == TOM_ERROR_ARGUMENT);
        CHECK(tom_stream_append(NULL, bytes, 1) == TOM_ERROR_ARGUMENT);
        CHECK(tom_stream_next_boundary(NULL) == 0 && tom_stream_chunk_count(NULL) == 0);
    }
    free(bytes);
    tom_file_close(ordinary);

    if (argc > 3) { /* a textured GLB: the first chunk decodes before the image arrives */
        tom_stream_codecs codecs;
        tom_stream* box = NULL;
        tom_file* first = NULL;
        tom_file* whole = NULL;
        tom_stream_chunk chunk;
        bytes = read_all(argv[3], &size);
        CHECK(bytes != NULL);
        codecs.decode_vertices = decode_vertices, codecs.decode_indices = decode_indices, codecs.context = &calls;
        CHECK(tom_stream_create(&codecs, argv[3], &box) == TOM_OK);
        if (bytes && box) {
            CHECK(tom_stream_append(box, bytes, 64) == TOM_OK);
            CHECK(tom_stream_append(box, bytes + 64, (size_t)(tom_stream_next_boundary(box) - 64)) == TOM_OK);
            CHECK(tom_stream_chunk_at(box, 0, &chunk) == TOM_OK);
            CHECK(tom_stream_append(box, bytes + chunk.begin_byte, (size_t)(chunk.end_byte - chunk.begin_byte)) == TOM_OK);
            CHECK(tom_stream_snapshot(box, &first) == TOM_OK);
            CHECK(first && tom_file_image_count(first) == 0 && tom_file_material_count(first) == 1);
            CHECK(tom_stream_next_boundary(box) > chunk.end_byte + 1000); /* then the deferred block: the image */
            CHECK(tom_stream_append(box, bytes + chunk.end_byte, size - (size_t)chunk.end_byte) == TOM_OK);
            CHECK(tom_stream_complete(box));
            CHECK(tom_stream_snapshot(box, &whole) == TOM_OK);
            CHECK(whole && tom_file_image_count(whole) == 1);
        }
        tom_file_close(first);
        tom_file_close(whole);
        tom_stream_destroy(box);
        free(bytes);
    }
    printf("capi_stream_test: %d checks, %d failed\n", checks, failures);
    return failures ? 1 : 0;
}
