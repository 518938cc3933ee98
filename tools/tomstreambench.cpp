// tomstreambench: the streamed layout against meshoptimizer's codecs on the same mesh, in one run.
// For each .tom (ordinary or streamed): the stream's bytes and decode speed (tom::StreamDecoder
// over every byte, then the .tom image of the whole; and progressively, fed to each chunk boundary
// with an image after every chunk, as a viewer that redraws each chunk uses it), and as the
// reference the full-detail mesh
// quantized the same way, vertex-cache and fetch optimized and encoded with meshoptimizer's index
// and vertex codecs (what gltfpack -cc stores for one level), decoded by meshoptimizer.
// Medians of --repeats runs. --reference-out DIR writes both sides' bytes for the browser's
// measurement of the same (scripts/bench-web.sh): NAME.stream.tom, and NAME.meshopt.bin with
// NAME.meshopt.json (per mesh its counts and where its index, position and normal blocks lie).

#include <meshoptimizer.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "tom/errors.h"
#include "tom/extract.h"
#include "tom/format.h"
#include "tom/stream/stream_file.h"
#include "tool_common.h"

namespace {

using Clock = std::chrono::steady_clock;

std::vector<uint8_t> read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw tom::IoError("cannot open " + path);
    return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

/// meshoptimizer's encoding of the full-detail mesh 0: indices, 14-bit positions (8-byte
/// elements) and 8-bit octahedral-size normals (4-byte elements), as gltfpack stores a level.
struct Reference {
    std::vector<uint8_t> indices, positions, normals;
    size_t index_count = 0, vertex_count = 0;
    size_t bytes() const { return indices.size() + positions.size() + normals.size(); }
};

Reference reference(const tom::MeshView& m) {
    Reference r;
    std::vector<uint32_t> idx(3 * size_t(m.triangle_count));
    idx.resize(3 * size_t(tom::extract(m, m.vertex_count, idx.data(), idx.size()).triangle_count));
    meshopt_optimizeVertexCache(idx.data(), idx.data(), idx.size(), m.vertex_count);
    std::vector<uint16_t> pos(4 * size_t(m.vertex_count), 0);
    std::vector<uint8_t> nrm(4 * size_t(m.vertex_count), 0);
    float lo[3], extent = 0;
    for (int k = 0; k < 3; ++k) lo[k] = m.bounds_min[k], extent = std::max(extent, m.bounds_max[k] - m.bounds_min[k]);
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        for (int k = 0; k < 3; ++k) pos[4 * v + k] = uint16_t(meshopt_quantizeUnorm((m.positions[3 * v + k] - lo[k]) / (extent > 0 ? extent : 1), 14));
        if (m.normals)
            for (int k = 0; k < 3; ++k) nrm[4 * v + k] = uint8_t(meshopt_quantizeSnorm(m.normals[3 * v + k], 8));
    }
    std::vector<uint32_t> remap(m.vertex_count);
    r.vertex_count = meshopt_optimizeVertexFetchRemap(remap.data(), idx.data(), idx.size(), m.vertex_count);
    meshopt_remapIndexBuffer(idx.data(), idx.data(), idx.size(), remap.data());
    meshopt_remapVertexBuffer(pos.data(), pos.data(), m.vertex_count, 8, remap.data());
    meshopt_remapVertexBuffer(nrm.data(), nrm.data(), m.vertex_count, 4, remap.data());
    r.index_count = idx.size();
    r.indices.resize(meshopt_encodeIndexBufferBound(idx.size(), r.vertex_count));
    r.indices.resize(meshopt_encodeIndexBuffer(r.indices.data(), r.indices.size(), idx.data(), idx.size()));
    r.positions.resize(meshopt_encodeVertexBufferBound(r.vertex_count, 8));
    r.positions.resize(meshopt_encodeVertexBuffer(r.positions.data(), r.positions.size(), pos.data(), r.vertex_count, 8));
    if (m.normals) {
        r.normals.resize(meshopt_encodeVertexBufferBound(r.vertex_count, 4));
        r.normals.resize(meshopt_encodeVertexBuffer(r.normals.data(), r.normals.size(), nrm.data(), r.vertex_count, 4));
    }
    return r;
}

struct Figures {
    std::string file;
    uint64_t stream_bytes = 0, first_chunk_bytes = 0;
    uint32_t vertices = 0, triangles = 0;
    double decode_s = 0, assemble_s = 0, progressive_s = 0;
    size_t snapshots = 0;  // images made by the progressive run
    size_t reference_bytes = 0;
    double reference_s = 0;
};

/// The stream and the reference's blocks, for scripts/bench-web.sh.
void write_reference(const std::string& dir, const std::string& path, const std::vector<uint8_t>& stream, const std::vector<Reference>& refs) {
    const std::string name = std::filesystem::path(path).stem().string();
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/" + name + ".stream.tom", std::ios::binary).write(reinterpret_cast<const char*>(stream.data()), std::streamsize(stream.size()));
    std::ofstream bin(dir + "/" + name + ".meshopt.bin", std::ios::binary);
    nlohmann::ordered_json meshes = nlohmann::json::array();
    size_t at = 0;
    for (const Reference& r : refs) {
        nlohmann::ordered_json m{{"index_count", r.index_count}, {"vertex_count", r.vertex_count}};
        for (const auto& [key, block] : {std::pair{"indices", &r.indices}, std::pair{"positions", &r.positions}, std::pair{"normals", &r.normals}}) {
            m[key] = {at, block->size()};
            bin.write(reinterpret_cast<const char*>(block->data()), std::streamsize(block->size()));
            at += block->size();
        }
        meshes.push_back(m);
    }
    std::ofstream index(dir + "/" + name + ".meshopt.json");
    index << nlohmann::ordered_json{{"stream", name + ".stream.tom"}, {"blocks", name + ".meshopt.bin"}, {"meshes", meshes}}.dump() << "\n";
    if (!bin || !index) throw tom::IoError("cannot write the reference into " + dir);
}

/// The stream fed to one chunk boundary at a time, an image (StreamDecoder::file()) after each
/// chunk: the seconds of the whole, and the number of images.
std::pair<double, size_t> progressive(const std::vector<uint8_t>& bytes, const std::string& path) {
    const auto t0 = Clock::now();
    tom::StreamDecoder d(tom::meshopt_codecs(), path);
    size_t images = 0;
    for (uint64_t at = 0; at < bytes.size();) {
        const uint64_t next = std::min<uint64_t>(std::max<uint64_t>(d.next_boundary(), at + 1), bytes.size());
        const size_t before = d.decoded_chunks();
        d.append(bytes.data() + at, next - at);
        at = next;
        if (d.decoded_chunks() > before) {
            const tom::File snapshot = d.file();
            ++images;
        }
    }
    return {std::chrono::duration<double>(Clock::now() - t0).count(), images};
}

Figures measure(const std::string& path, int repeats, const std::string& reference_out) {
    Figures f;
    f.file = path;
    std::vector<uint8_t> bytes = read_bytes(path);
    if (!tom::is_stream(bytes.data(), bytes.size())) bytes = tom::encode_stream(bytes.data(), bytes.size(), {}, path);
    f.stream_bytes = bytes.size();
    std::vector<double> decode, assemble, ref;
    std::vector<uint8_t> image;
    {  // a run untimed: the first one pays the allocator's growth (fresh pages for the image),
        // which only the first file of a run would pay otherwise
        tom::StreamDecoder d(tom::meshopt_codecs(), path);
        d.append(bytes.data(), bytes.size());
        image = d.tom_bytes();
    }
    for (int r = 0; r < repeats; ++r) {
        auto t0 = Clock::now();
        tom::StreamDecoder d(tom::meshopt_codecs(), path);
        d.append(bytes.data(), bytes.size());
        decode.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        t0 = Clock::now();
        image = d.tom_bytes();
        assemble.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        f.first_chunk_bytes = d.chunks().front().end_byte;
    }
    std::vector<double> progressive_runs;
    for (int r = 0; r < repeats; ++r) {
        const auto [seconds, images] = progressive(bytes, path);
        progressive_runs.push_back(seconds), f.snapshots = images;
    }
    const tom::File file = tom::File::from_bytes(image.data(), image.size(), path);
    for (uint32_t i = 0; i < file.mesh_count(); ++i) f.vertices += file.mesh(i).vertex_count, f.triangles += file.mesh(i).triangle_count;
    // the reference: every mesh of the file, decoded by meshoptimizer
    std::vector<Reference> refs;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) refs.push_back(reference(file.mesh(i)));
    for (const Reference& r : refs) f.reference_bytes += r.bytes();
    if (!reference_out.empty()) write_reference(reference_out, path, bytes, refs);
    for (int k = 0; k < repeats; ++k) {
        const auto t0 = Clock::now();
        for (const Reference& r : refs) {
            std::vector<uint32_t> idx(r.index_count);
            std::vector<uint8_t> pos(8 * r.vertex_count), nrm(4 * r.vertex_count);
            bool ok = meshopt_decodeIndexBuffer(idx.data(), idx.size(), 4, r.indices.data(), r.indices.size()) == 0;
            ok = ok && meshopt_decodeVertexBuffer(pos.data(), r.vertex_count, 8, r.positions.data(), r.positions.size()) == 0;
            if (!r.normals.empty()) ok = ok && meshopt_decodeVertexBuffer(nrm.data(), r.vertex_count, 4, r.normals.data(), r.normals.size()) == 0;
            if (!ok) throw tom::InternalError("tomstreambench: meshoptimizer does not decode what it encoded");
        }
        ref.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    f.decode_s = tools::median(decode), f.assemble_s = tools::median(assemble), f.reference_s = tools::median(ref);
    f.progressive_s = tools::median(progressive_runs);
    return f;
}

} // namespace

int main(int argc, char** argv) {
    std::vector<std::string> files;
    int repeats = 5;
    bool json = false;
    std::string reference_out;
    CLI::App app{"Streamed .tom files against meshoptimizer's codecs on the same meshes: bytes and decode speed"};
    app.add_option("files", files, ".tom files, ordinary (streamed here with the default options) or streamed")->required();
    app.add_option("-r,--repeats", repeats, "Runs per figure; medians are reported (default 5)")->check(CLI::Range(1, 1000));
    app.add_flag("--json", json, "One JSON object per file (one per line) instead of the table");
    app.add_option("--reference-out", reference_out, "Also write each file's stream and meshoptimizer blocks into this folder (for scripts/bench-web.sh)");
    app.footer("Exit codes: 0 ok, 1 a file could not be read, 2 usage error.\nExample: tomstreambench out/bunny00.tom");
    if (const int code = tools::parse(app, argc, argv); code >= 0) return code;
    if (!json)
        std::printf("%-28s %10s %10s %7s %10s %10s %10s %10s %10s %8s %14s\n", "file", "triangles", "stream B", "first", "meshopt B", "decode ms", "+image ms",
                    "MB/s", "Mtri/s", "x meshopt", "progressive ms");
    for (const std::string& path : files) {
        try {
            const Figures f = measure(path, repeats, reference_out);
            const double total = f.decode_s + f.assemble_s;
            const double speed = f.triangles / total, ref_speed = f.triangles / f.reference_s;
            if (json) {
                nlohmann::ordered_json j{{"file", f.file},
                                         {"vertices", f.vertices},
                                         {"triangles", f.triangles},
                                         {"stream_bytes", f.stream_bytes},
                                         {"first_chunk_bytes", f.first_chunk_bytes},
                                         {"meshopt_bytes", f.reference_bytes},
                                         {"decode_ms", f.decode_s * 1e3},
                                         {"image_ms", f.assemble_s * 1e3},
                                         {"decode_mb_per_s", f.stream_bytes / total / 1e6},
                                         {"decode_tris_per_s", speed},
                                         {"meshopt_decode_ms", f.reference_s * 1e3},
                                         {"meshopt_tris_per_s", ref_speed},
                                         {"speed_over_meshopt", speed / ref_speed},
                                         {"progressive_ms", f.progressive_s * 1e3},
                                         {"progressive_images", f.snapshots}};
                std::printf("%s\n", j.dump().c_str());
            } else {
                std::printf("%-28.28s %10u %10llu %6.1f%% %10zu %10.2f %10.2f %10.1f %10.2f %8.2f %14.2f\n", f.file.c_str(), f.triangles,
                            static_cast<unsigned long long>(f.stream_bytes), 100.0 * double(f.first_chunk_bytes) / double(f.stream_bytes), f.reference_bytes,
                            f.decode_s * 1e3, f.assemble_s * 1e3, f.stream_bytes / total / 1e6, speed / 1e6, speed / ref_speed, f.progressive_s * 1e3);
            }
        } catch (const std::exception& e) {
            std::fprintf(stderr, "error: %s\n", e.what());
            return tools::exit_failed;
        }
    }
    return tools::exit_ok;
}
