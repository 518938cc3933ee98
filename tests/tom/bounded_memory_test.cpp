// Memory bounded by the input: files of a few hundred bytes that announce two billion vertices,
// faces or bytes, or a corner count of -1, fed to every reader in a child process whose address
// space is limited (setrlimit) to what it has plus 512 MB. Each must be rejected with an error
// naming the file and the field before anything of the announced size is allocated; a
// std::bad_alloc, a signal or a mesh is a failure. (The calibration and scene readers announce
// no sizes: they read line by line.)

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/builder/generate.h"
#include "tom/builder/writer.h"
#include "tom/errors.h"
#include "tom/format.h"
#include "tom/io/import.h"

namespace {

namespace fs = std::filesystem;

struct HostileFile {
    std::string name;
    std::string bytes;
    std::string expect;  // in the message, after the file's path
};

std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string floats(std::initializer_list<float> values) {
    std::string s;
    for (float f : values) s.append(reinterpret_cast<const char*>(&f), 4);
    return s;
}

// One file per reader and per field that announces a size.
std::vector<HostileFile> hostile_files() {
    const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
    auto ply = [](const char* format, uint32_t vertices, uint32_t faces, const char* count_type) {
        return std::string("ply\nformat ") + format + " 1.0\nelement vertex " + std::to_string(vertices) +
               "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces) + "\nproperty list " + count_type +
               " int vertex_indices\nend_header\n";
    };
    const std::string tri_binary = floats({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string buffer = "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";  // the triangle
    auto gltf = [&](const std::string& count, const std::string& buffer_bytes, const std::string& view_bytes) {
        return R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + buffer_bytes + R"(,"uri":")" + buffer + R"("}],)" +
               R"("bufferViews":[{"buffer":0,"byteLength":)" + view_bytes + R"(}],)" +
               R"("accessors":[{"bufferView":0,"componentType":5126,"count":)" + count + R"(,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)" +
               R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]})";
    };
    std::string json = gltf("3", "36", "36");
    json.append((4 - json.size() % 4) % 4, ' ');
    const std::string glb = le32(0x46546C67) + le32(2) + le32(2000000000) + le32(2000000000) + le32(0x4E4F534A) + json;
    return {
        {"vertices.off", "OFF\n2000000000 1 0\n" + tri + "3 0 1 2\n", ":2: 2000000000 vertices and 1 faces cannot fit"},
        {"faces.off", "OFF\n3 2000000000 0\n" + tri + "3 0 1 2\n", ":2: 3 vertices and 2000000000 faces cannot fit"},
        {"corners.off", "OFF\n3 1 0\n" + tri + "-1 0 1 2\n", ":6: face 0 announces '-1' corners"},
        {"binary.off", "OFF BINARY\n" + le32(2000000000) + le32(1) + le32(0) + std::string(40, '\0'), ":2: 2000000000 vertices and 1 faces cannot fit"},
        {"vertices.ply", ply("ascii", 2000000000, 1, "uchar") + tri + "3 0 1 2\n", ":3: 2000000000 vertex elements cannot fit"},
        {"faces.ply", ply("ascii", 3, 2000000000, "uchar") + tri + "3 0 1 2\n", ":7: 2000000000 face elements cannot fit"},
        {"empty-elements.ply", "ply\nformat binary_little_endian 1.0\nelement note 2000000000\n" + ply("binary_little_endian", 3, 1, "uchar").substr(36) + tri_binary + "\3" + le32(0) + le32(1) + le32(2),
         ":3: 2000000000 note elements without properties in a file of"},
        {"corners.ply", ply("ascii", 3, 1, "int") + tri + "-1 0 1 2\n", ":13: face 0: the list vertex_indices announces '-1' items"},
        {"corners-unsigned.ply", ply("ascii", 3, 1, "uint") + tri + "4000000000 0 1 2\n", ":13: face 0: the list vertex_indices announces '4000000000' items"},
        {"vertices-binary.ply", ply("binary_little_endian", 2000000000, 1, "uchar") + tri_binary + "\3" + le32(0) + le32(1) + le32(2),
         ":3: 2000000000 vertex elements of at least 12 bytes cannot fit"},
        {"corners-binary.ply", ply("binary_little_endian", 3, 1, "int") + tri_binary + le32(0xFFFFFFFFu) + le32(0) + le32(1) + le32(2),
         ":7: face 0: the list vertex_indices announces -1 items"},
        {"triangles.stl", std::string(80, '\0') + le32(2000000000) + std::string(50, '\0'), ":1: neither ASCII STL (starting with 'solid') nor binary STL"},
        {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2000000000\n", ":4: a face refers to vertex '2000000000', the file has 3"},
        {"count.gltf", gltf("2000000000", "36", "36"), ": mesh 0 'mesh0' primitive 0: POSITION accessor 0: 2000000000 elements need 24000000000 bytes"},
        {"view.gltf", gltf("3", "36", "2000000000"), ": $.bufferViews[0]: bytes up to 2000000000 of buffer 0, which has 36"},
        {"chunk.glb", glb, ": GLB header declares 2000000000 bytes, the file has"},
    };
}

// A real .tom whose header announces two billion meshes and sections, and one whose mesh
// announces two billion vertices, with every checksum recomputed so the size checks must catch them.
std::vector<HostileFile> hostile_tom_files() {
    const tom::TomMesh built = tom::build(tom::make_grid(4, 4, 0.0f));
    const std::vector<uint8_t> bytes = tom::serialize({built});
    const std::string good(bytes.begin(), bytes.end());
    auto put32 = [](std::string& b, size_t at, uint32_t v) { std::memcpy(&b[at], &v, 4); };
    auto get32 = [](const std::string& b, size_t at) {
        uint32_t v;
        std::memcpy(&v, &b[at], 4);
        return v;
    };
    auto fix_header = [&](std::string& b) { put32(b, 44, tom::crc32(b.data(), 44)); };
    std::string meshes = good;
    put32(meshes, 24, 2000000000);
    fix_header(meshes);
    std::string sections = good;
    put32(sections, 28, 2000000000);
    fix_header(sections);
    // the good file with one field of the mesh header set to `value`, checksums recomputed;
    // `at` receives the field's file offset
    const uint32_t section_count = get32(good, 28);
    auto with_mesh_field = [&](size_t field, uint32_t value, size_t& at) {
        std::string b = good;
        for (uint32_t s = 0; s < section_count; ++s) {
            const size_t entry = 64 + 32 * size_t(s);
            if (good.compare(entry, 4, "MESH") != 0) continue;
            uint64_t offset, length;
            std::memcpy(&offset, &good[entry + 8], 8);
            std::memcpy(&length, &good[entry + 16], 8);
            at = size_t(offset) + field;
            put32(b, at, value);
            put32(b, entry + 24, tom::crc32(&b[size_t(offset)], size_t(length)));
        }
        put32(b, 40, tom::crc32(&b[64], 32 * size_t(section_count)));
        fix_header(b);
        return b;
    };
    size_t at = 0;
    const std::string vertices = with_mesh_field(0, 2000000000, at);
    // the fuzzing run's file: a material index in a file without materials sent the exporters
    // into a loop up to it
    const std::string material = with_mesh_field(16, 1196310868, at);
    return {{"meshes.tom", meshes, ": byte 24, mesh_count: 2000000000"},
            {"sections.tom", sections, ": byte 32, section_table:"},
            {"vertices.tom", vertices, ": byte 204, mesh 0 index_size:"},  // 2 bytes cannot index 2^31 vertices
            {"material.tom", material, ": byte " + std::to_string(at) + ", mesh 0 material: material 1196310868 is not among the 0 stored"}};
}

// Runs `read_file` on each file in a child whose address space is capped; returns what each gave:
// the error's message, or "LOADED", "bad_alloc: ..." or "exception: ..."; "SIGNAL n" for the
// child's end if it did not exit 0.
template <class Read>
std::vector<std::string> read_under_limit(const std::vector<std::string>& paths, Read read_file) {
    int pipe_fds[2];
    REQUIRE(pipe(pipe_fds) == 0);
    const pid_t child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
        close(pipe_fds[0]);
        long pages = 0;
        if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
            if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
            std::fclose(statm);
        }
        const rlim_t limit = rlim_t(pages) * rlim_t(sysconf(_SC_PAGESIZE)) + (rlim_t(512) << 20);
        const rlimit r{limit, limit};
        if (setrlimit(RLIMIT_AS, &r) != 0) _exit(3);
        std::string out;
        for (const std::string& path : paths) {
            std::string result;
            try {
                read_file(path);
                result = "LOADED";
            } catch (const tom::Error& e) {
                result = e.what();
            } catch (const std::bad_alloc& e) {
                result = std::string("bad_alloc: ") + e.what();
            } catch (const std::exception& e) {
                result = std::string("exception: ") + e.what();
            }
            for (char& c : result)
                if (c == '\n') c = ' ';
            out += result + "\n";
        }
        for (size_t done = 0; done < out.size();) {
            const ssize_t n = write(pipe_fds[1], out.data() + done, out.size() - done);
            if (n <= 0) _exit(4);
            done += size_t(n);
        }
        _exit(0);
    }
    close(pipe_fds[1]);
    std::string text;
    char chunk[4096];
    for (ssize_t n; (n = ::read(pipe_fds[0], chunk, sizeof chunk)) > 0;) text.append(chunk, size_t(n));
    close(pipe_fds[0]);
    int status = 0;
    waitpid(child, &status, 0);
    std::vector<std::string> results;
    for (size_t at = 0, end; (end = text.find('\n', at)) != std::string::npos; at = end + 1) results.push_back(text.substr(at, end - at));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        results.push_back(WIFSIGNALED(status) ? "SIGNAL " + std::to_string(WTERMSIG(status)) : "EXIT " + std::to_string(WEXITSTATUS(status)));
    return results;
}

std::vector<std::string> write_all(const fs::path& dir, const std::vector<HostileFile>& files) {
    fs::create_directories(dir);
    std::vector<std::string> paths;
    for (const HostileFile& f : files) {
        paths.push_back((dir / f.name).string());
        std::ofstream(paths.back(), std::ios::binary) << f.bytes;
    }
    return paths;
}

} // namespace

TEST_CASE("files announcing two billion elements are rejected under a 512 MB address-space limit", "[import][bounded]") {
    const fs::path dir = fs::temp_directory_path() / "tom_bounded_import";
    const std::vector<HostileFile> files = hostile_files();
    const std::vector<std::string> paths = write_all(dir, files);
    const std::vector<std::string> results = read_under_limit(paths, [](const std::string& p) { (void)tom::import_file(p); });
    REQUIRE(results.size() == files.size());  // else the child died: the last entry says how
    for (size_t i = 0; i < files.size(); ++i) {
        INFO(files[i].name << ": " << results[i]);
        CHECK(results[i].find(paths[i] + files[i].expect) != std::string::npos);
    }
    fs::remove_all(dir);
}

TEST_CASE(".tom files announcing two billion meshes, sections or vertices are rejected under the limit", "[format][bounded]") {
    const fs::path dir = fs::temp_directory_path() / "tom_bounded_tom";
    const std::vector<HostileFile> files = hostile_tom_files();
    const std::vector<std::string> paths = write_all(dir, files);
    for (const bool mapped : {true, false}) {
        INFO((mapped ? "mapped" : "from bytes"));
        const std::vector<std::string> results = read_under_limit(paths, [mapped](const std::string& p) {
            if (mapped) {
                (void)tom::File::open(p);
                return;
            }
            std::ifstream in(p, std::ios::binary);
            const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
            (void)tom::File::from_bytes(reinterpret_cast<const uint8_t*>(b.data()), b.size(), p);
        });
        REQUIRE(results.size() == files.size());
        for (size_t i = 0; i < files.size(); ++i) {
            INFO(files[i].name << ": " << results[i]);
            CHECK(results[i].rfind(paths[i] + files[i].expect, 0) == 0);  // a FormatError naming the file
            CHECK(results[i].find("rule") != std::string::npos);
        }
    }
    fs::remove_all(dir);
}
