#include "support.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include <catch2/catch.hpp>

#include "tom/extract.h"
#include "tom/builder/generate.h"
#ifdef TOM_TEST_NO_IMPORT
#include "tom/format.h"
#else
#include "tom/io/import.h"
#endif

namespace test {

std::string sample(const std::string& relative) {
    const std::string path = std::string(TOM_DATA_DIR) + "/" + relative;
    INFO("sample " << path << " is missing: run scripts/fetch-samples.sh");
    REQUIRE(std::filesystem::exists(path));
    return path;
}

namespace {

NamedMesh named(std::string name, tom::Mesh mesh, bool closed, int euler = 0) {
    tom::clean_mesh(mesh);
    NamedMesh n;
    n.name = std::move(name);
    n.mesh = std::move(mesh);
    n.closed_manifold = closed;
    n.euler = euler;
    return n;
}

void append(tom::Mesh& dst, const tom::Mesh& src, float dx) {
    const uint32_t base = dst.vertex_count();
    for (size_t i = 0; i < src.positions.size(); i += 3) dst.positions.insert(dst.positions.end(), {src.positions[i] + dx, src.positions[i + 1], src.positions[i + 2]});
    for (uint32_t i : src.indices) dst.indices.push_back(i + base);
}

} // namespace

std::vector<NamedMesh> generated_meshes() {
    std::vector<NamedMesh> out;
    out.push_back(named("sphere 12x16", tom::make_sphere(12, 16), true, 2));
    out.push_back(named("bumpy sphere 40x40", tom::make_sphere(40, 40, 1.0f, 0.1f), true, 2));
    {
        // a UV sphere cut along a meridian, as textured spheres are: the seam vertices are
        // duplicated (same position, u = 0 and u = 1); welded it is a closed sphere
        tom::Mesh s = tom::make_sphere(14, 18);
        const uint32_t rings = 14, segments = 18;
        auto ring_vertex = [&](uint32_t i, uint32_t j) { return 1 + (i - 1) * segments + (j % segments); };
        s.texcoords.assign(size_t(s.vertex_count()) * 2, 0.0f);
        std::vector<uint32_t> copy(rings, 0);
        for (uint32_t i = 1; i < rings; ++i) {
            const uint32_t v = ring_vertex(i, 0);
            copy[i] = s.vertex_count();
            s.positions.insert(s.positions.end(), {s.positions[3 * v], s.positions[3 * v + 1], s.positions[3 * v + 2]});
            s.texcoords.insert(s.texcoords.end(), {1.0f, float(i) / rings});
        }
        for (uint32_t v = 1; v < 1 + (rings - 1) * segments; ++v) s.texcoords[2 * v] = float((v - 1) % segments) / segments;
        // triangles of the last column (j = segments - 1 to j = 0) use the u = 1 copies
        for (size_t t = 0; t < s.indices.size(); t += 3) {
            bool last_column = false;
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = s.indices[t + k];
                if (v >= 1 && v < 1 + (rings - 1) * segments && (v - 1) % segments == segments - 1) last_column = true;
            }
            if (!last_column) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = s.indices[t + k];
                if (v >= 1 && v < 1 + (rings - 1) * segments && (v - 1) % segments == 0) s.indices[t + k] = copy[1 + (v - 1) / segments];
            }
        }
        out.push_back(named("sphere with a UV seam", s, true, 2));
    }
    out.push_back(named("torus 24x12", tom::make_torus(24, 12), true, 0));
    out.push_back(named("grid 20x20 (border)", tom::make_grid(20, 20), false));
    {
        tom::Mesh two = tom::make_sphere(8, 10);
        append(two, tom::make_torus(16, 8), 3.0f);
        out.push_back(named("sphere + torus (two components)", two, true, 2));
    }
    {
        // the grid cut in two along x = 0.5 with its seam vertices duplicated: the halves must
        // stay stitched (coincident copies never separate)
        tom::Mesh g = tom::make_grid(16, 16);
        const uint32_t n = g.vertex_count();
        for (uint32_t v = 0; v < n; ++v) g.positions.insert(g.positions.end(), {g.positions[3 * v], g.positions[3 * v + 1], g.positions[3 * v + 2]});
        for (size_t t = 0; t < g.indices.size(); t += 3) {
            float cx = 0;
            for (int k = 0; k < 3; ++k) cx += g.positions[3 * g.indices[t + k]];
            if (cx / 3 > 0.5f)
                for (int k = 0; k < 3; ++k) g.indices[t + k] += n;  // right half uses the copies
        }
        out.push_back(named("grid with duplicated seam", g, false));
    }
    {
        // three sheets sharing one edge (non-manifold), plus a bow-tie vertex
        tom::Mesh f = tom::make_grid(6, 6);
        tom::Mesh fan;
        fan.positions = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1, 2, 0.5f, 0, 2, -0.5f, 0};
        fan.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 5, 6};
        append(f, fan, 2.0f);
        out.push_back(named("non-manifold fan + bow-tie", f, false));
    }
    {
        // degenerate input: repeated indices (dropped by clean_mesh), zero-area slivers,
        // duplicate triangles
        tom::Mesh d = tom::make_grid(10, 10);
        d.indices.insert(d.indices.end(), {0, 0, 1, 5, 6, 6});
        const size_t tris = d.indices.size() / 3;
        d.indices.insert(d.indices.end(), d.indices.begin() + 3 * 10, d.indices.begin() + 3 * 14);  // duplicates
        // an isolated zero-area sliver (three collinear vertices)
        const uint32_t base = d.vertex_count();
        d.positions.insert(d.positions.end(), {2, 0, 0, 3, 0, 0, 4, 0, 0});
        d.indices.insert(d.indices.end(), {base, base + 1, base + 2});
        (void)tris;
        out.push_back(named("degenerate + duplicate triangles", d, false));
    }
    return out;
}

#ifdef TOM_TEST_NO_IMPORT
namespace {
// Where the importers are not built (the Windows build), the real meshes come from .tom files
// that tombuild made of the same samples, in TOM_REAL_TOM_DIR (scripts/portable.sh): each
// mesh at full resolution, its vertices in resolution order.
std::vector<tom::Mesh> import_from_tom(const std::string& relative) {
    const char* dir = std::getenv("TOM_REAL_TOM_DIR");
    INFO("TOM_REAL_TOM_DIR must name the folder of the samples' .tom files (scripts/portable.sh makes it)");
    REQUIRE(dir != nullptr);
    std::string stem = relative.substr(relative.find_last_of('/') + 1);
    stem = stem.substr(0, stem.find_last_of('.'));
    const std::string path = std::string(dir) + "/" + stem + ".tom";
    INFO("missing " << path);
    REQUIRE(std::filesystem::exists(path));
    const tom::File file = tom::File::open(path);
    std::vector<tom::Mesh> meshes;
    for (uint32_t i = 0; i < file.mesh_count(); ++i) {
        const tom::MeshView& v = file.mesh(i);
        tom::Mesh m;
        m.name = std::string(v.name);
        m.positions.assign(v.positions, v.positions + 3 * size_t(v.vertex_count));
        if (v.normals) m.normals.assign(v.normals, v.normals + 3 * size_t(v.vertex_count));
        if (v.texcoords) m.texcoords.assign(v.texcoords, v.texcoords + 2 * size_t(v.vertex_count));
        m.indices.resize(3 * size_t(v.triangle_count));
        tom::extract(v, v.vertex_count, m.indices.data(), m.indices.size());
        meshes.push_back(std::move(m));
    }
    return meshes;
}
} // namespace
#endif

std::vector<NamedMesh> real_meshes() {
    std::vector<NamedMesh> out;
    auto load = [&](const std::string& rel, bool closed, int euler, int primitive = -1) {
#ifdef TOM_TEST_NO_IMPORT
        std::vector<tom::Mesh> meshes = import_from_tom(rel);
#else
        std::vector<tom::Mesh> meshes = tom::import_file(sample(rel)).meshes;
#endif
        REQUIRE(!meshes.empty());
        size_t pick = 0;
        if (primitive >= 0)
            for (size_t i = 0; i < meshes.size(); ++i)
                if (meshes[i].triangle_count() > meshes[pick].triangle_count()) pick = i;
        out.push_back(named(rel, std::move(meshes[pick]), closed, euler));
    };
    load("meshes/bunny00.off", true, 2);
    load("meshes/fandisk.off", true, 2);
    load("meshes/cow.off", false, 0);
    load("meshes/elephant.off", false, 0);
    load("assimp/OBJ/WusonOBJ.obj", false, 0);
    load("assimp/OBJ/spider.obj", false, 0);
    load("assimp/STL/Spider_binary.stl", false, 0);
    load("assimp/PLY/cube_binary.ply", false, 0);
    load("assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", false, 0, 1);
    return out;
}

std::vector<float> snap_copies(const float* positions, size_t vertex_count) {
    std::vector<float> out(positions, positions + 3 * vertex_count);
    if (vertex_count == 0) return out;
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = hi[k] = positions[k];
    for (size_t v = 0; v < vertex_count; ++v)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(positions[3 * v + k])), hi[k] = std::max(hi[k], double(positions[3 * v + k]));
    const double tol = 1e-6 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double cell = tol > 0 ? tol : 1.0;
    std::vector<size_t> parent(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) parent[v] = v;
    auto find = [&](size_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    std::map<std::array<int64_t, 3>, std::vector<size_t>> cells;
    auto key = [&](size_t v) {
        std::array<int64_t, 3> c;
        for (int k = 0; k < 3; ++k) c[k] = int64_t(std::floor((double(positions[3 * v + k]) - lo[k]) / cell));
        return c;
    };
    for (size_t v = 0; v < vertex_count; ++v) cells[key(v)].push_back(v);
    for (size_t v = 0; v < vertex_count; ++v) {
        const std::array<int64_t, 3> c = key(v);
        for (int64_t dx = -1; dx <= 1; ++dx)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dz = -1; dz <= 1; ++dz) {
                    const auto it = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
                    if (it == cells.end()) continue;
                    for (const size_t w : it->second) {
                        double d2 = 0;
                        for (int k = 0; k < 3; ++k) d2 += std::pow(double(positions[3 * v + k]) - positions[3 * w + k], 2);
                        if (d2 <= tol * tol) parent[find(v)] = find(w);
                    }
                }
    }
    std::map<size_t, std::array<float, 3>> smallest;
    for (size_t v = 0; v < vertex_count; ++v) {
        const std::array<float, 3> p = {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
        auto [it, fresh] = smallest.emplace(find(v), p);
        if (!fresh && p < it->second) it->second = p;
    }
    for (size_t v = 0; v < vertex_count; ++v) std::copy_n(smallest[find(v)].data(), 3, &out[3 * v]);
    return out;
}

Topology topology(const float* raw_positions, const uint32_t* indices, size_t triangle_count, bool weld) {
    // vertex id: welded by position (within the copy tolerance) or as given
    size_t vertex_count = 0;
    for (size_t c = 0; c < 3 * triangle_count; ++c) vertex_count = std::max<size_t>(vertex_count, size_t(indices[c]) + 1);
    const std::vector<float> snapped = weld ? snap_copies(raw_positions, vertex_count) : std::vector<float>();
    const float* positions = snapped.data();
    std::map<std::array<float, 3>, int> weld_id;
    auto id = [&](uint32_t v) -> int64_t {
        if (!weld) return v;
        const std::array<float, 3> p = {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
        auto it = weld_id.emplace(p, int(weld_id.size())).first;
        return it->second;
    };
    std::map<std::pair<int64_t, int64_t>, int> edges;
    std::set<int64_t> verts;
    for (size_t t = 0; t < triangle_count; ++t) {
        int64_t c[3];
        for (int k = 0; k < 3; ++k) c[k] = id(indices[3 * t + k]), verts.insert(c[k]);
        for (int k = 0; k < 3; ++k) ++edges[{std::min(c[k], c[(k + 1) % 3]), std::max(c[k], c[(k + 1) % 3])}];
    }
    Topology topo;
    topo.vertices = int(verts.size());
    topo.edges = int(edges.size());
    topo.faces = int(triangle_count);
    for (const auto& [e, count] : edges) {
        topo.border_edges += count == 1;
        topo.nonmanifold_edges += count > 2;
    }
    return topo;
}

std::vector<uint32_t> brute_force_active(const tom::MeshView& m, uint32_t n) {
    std::vector<uint32_t> out;
    for (uint32_t p = 0; p < tom::part_count(m); ++p) {
        const tom::Part part = tom::part_at(m, p);
        INFO("part " << p);
        brute_force_part(m, n, part.first_triangle, part.first_triangle + part.triangle_count, out);
    }
    return out;
}

void brute_force_part(const tom::MeshView& m, uint32_t n, uint32_t begin, uint32_t end, std::vector<uint32_t>& out) {
    bool ended = false;
    for (uint32_t t = begin; t < end; ++t) {
        uint32_t c[3];
        for (int k = 0; k < 3; ++k) {
            uint32_t v = m.corner(3 * t + k);
            while (v >= n) v = m.substitute_at(v);
            c[k] = v;
        }
        const bool alive = c[0] != c[1] && c[1] != c[2] && c[0] != c[2];
        if (alive) {
            INFO("triangle " << t << " is alive at resolution " << n << " after a dead one: not a prefix");
            REQUIRE(!ended);
            out.insert(out.end(), c, c + 3);
        } else {
            ended = true;
        }
    }
}

namespace {

std::array<float, 3> normal_of(const float* p, uint32_t a, uint32_t b, uint32_t c) {
    const float e1[3] = {p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]};
    const float e2[3] = {p[3 * c] - p[3 * a], p[3 * c + 1] - p[3 * a + 1], p[3 * c + 2] - p[3 * a + 2]};
    return {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
}

float dot3(const std::array<float, 3>& a, const std::array<float, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

std::array<uint32_t, 3> rotated(uint32_t a, uint32_t b, uint32_t c) {
    if (a <= b && a <= c) return {a, b, c};
    if (b <= a && b <= c) return {b, c, a};
    return {c, a, b};
}

} // namespace

namespace {

// The connected pieces of a mesh welded by position (within the copy tolerance): each input
// vertex's piece, and each piece's Euler characteristic.
struct InputPieces {
    std::vector<uint32_t> of;  // input vertex -> piece
    std::vector<int> euler;
};
InputPieces input_pieces(const tom::Mesh& in) {
    const std::vector<float> points = snap_copies(in.positions.data(), in.vertex_count());
    std::map<std::array<float, 3>, uint32_t> point_id;
    std::vector<uint32_t> point(in.vertex_count());
    for (uint32_t v = 0; v < in.vertex_count(); ++v) point[v] = point_id.emplace(std::array<float, 3>{points[3 * v], points[3 * v + 1], points[3 * v + 2]}, uint32_t(point_id.size())).first->second;
    std::vector<uint32_t> parent(point_id.size());
    for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (size_t c = 0; c < in.indices.size(); c += 3)
        for (int k = 1; k < 3; ++k) parent[find(point[in.indices[c + k]])] = find(point[in.indices[c]]);
    InputPieces out;
    out.of.resize(in.vertex_count());
    for (uint32_t v = 0; v < in.vertex_count(); ++v) out.of[v] = find(point[v]);
    out.euler.assign(point_id.size(), 0);
    std::set<uint32_t> used;
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (size_t c = 0; c < in.indices.size(); c += 3) {
        const uint32_t piece = out.of[in.indices[c]];
        ++out.euler[piece];  // F
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = point[in.indices[c + k]], b = point[in.indices[c + (k + 1) % 3]];
            if (used.insert(a).second) ++out.euler[piece];                               // V
            if (edges.insert({std::min(a, b), std::max(a, b)}).second) --out.euler[piece];  // E
        }
    }
    return out;
}

} // namespace

void check_invariants(const NamedMesh& input, const tom::TomMesh& built, bool topology_kept) {
    INFO("mesh: " << input.name);
    const tom::Mesh& in = input.mesh;
    const tom::MeshView m = built.view();
    const uint32_t N = m.vertex_count, s = m.min_vertex_count;
    REQUIRE(N == in.vertex_count());
    REQUIRE(m.triangle_count == in.triangle_count());
    REQUIRE(s >= 1);
    REQUIRE(s <= N);

    // substitute[i] < i for removed vertices, survivors point to themselves
    for (uint32_t i = 0; i < N; ++i) {
        if (i < s)
            REQUIRE(built.substitute[i] == i);
        else
            REQUIRE(built.substitute[i] < i);
    }
    // the vertex order is a permutation carrying every attribute along
    std::vector<uint32_t> seen(N, 0);
    for (uint32_t i = 0; i < N; ++i) {
        const uint32_t o = built.original_index[i];
        REQUIRE(o < N);
        REQUIRE(seen[o]++ == 0);
        for (int k = 0; k < 3; ++k) REQUIRE(built.positions[3 * i + k] == in.positions[3 * o + k]);
        if (!in.normals.empty())
            for (int k = 0; k < 3; ++k) REQUIRE(built.normals[3 * i + k] == in.normals[3 * o + k]);
    }
    // full resolution reproduces the input triangles (as a multiset, under the permutation)
    {
        std::multiset<std::array<uint32_t, 3>> a, b;
        for (uint32_t t = 0; t < m.triangle_count; ++t) {
            const uint32_t* c = &built.triangles[3 * t];
            a.insert(rotated(built.original_index[c[0]], built.original_index[c[1]], built.original_index[c[2]]));
            b.insert(rotated(in.indices[3 * t], in.indices[3 * t + 1], in.indices[3 * t + 2]));
        }
        REQUIRE(a == b);
    }

    // sampled resolutions: brute force against extraction
    std::vector<uint32_t> resolutions = {s, N};
    for (int k = 1; k < 12; ++k) resolutions.push_back(s + uint32_t(uint64_t(N - s) * k / 12));
    resolutions.push_back(std::min(N, s + 1));
    for (uint32_t& n : resolutions)
        n = m.whole_groups_below(n);  // a resolution keeps both copies of a seam pair, or neither
    std::sort(resolutions.begin(), resolutions.end());
    resolutions.erase(std::unique(resolutions.begin(), resolutions.end()), resolutions.end());
    // coincident copies (attribute seams, duplicated input), to check they never separate
    std::map<std::array<float, 3>, std::vector<uint32_t>> copies;
    double diagonal = 0;
    for (int k = 0; k < 3; ++k) diagonal += std::pow(double(built.bounds_max[k]) - built.bounds_min[k], 2);
    diagonal = std::sqrt(diagonal);
    for (uint32_t v = 0; v < N; ++v) copies[{built.positions[3 * v], built.positions[3 * v + 1], built.positions[3 * v + 2]}].push_back(v);
    const Topology full_topo = topology(in.positions.data(), in.indices.data(), in.triangle_count(), true);
    const InputPieces pieces = input_pieces(in);
    uint32_t previous_count = 0;
    std::vector<uint32_t> buffer32(size_t(m.triangle_count) * 3 + 3, 0xDEADBEEF);
    for (uint32_t n : resolutions) {
        INFO("resolution " << n << " of " << N);
        const std::vector<uint32_t> expect = brute_force_active(m, n);
        const uint32_t count = uint32_t(expect.size() / 3);
        REQUIRE(tom::active_triangle_count(m, n) == count);
        REQUIRE(count >= previous_count);  // monotone in n
        previous_count = count;
        const tom::Extracted r = tom::extract(m, n, buffer32.data(), buffer32.size());
        REQUIRE(r.vertex_count == n);
        REQUIRE(r.triangle_count == count);
        REQUIRE(std::equal(expect.begin(), expect.end(), buffer32.begin()));
        REQUIRE(buffer32[expect.size()] == 0xDEADBEEF);  // nothing written past the triangles
        for (size_t i = 0; i < expect.size(); i += 3) {
            REQUIRE(expect[i] < n);
            REQUIRE(expect[i + 1] < n);
            REQUIRE(expect[i + 2] < n);
        }
        std::fill(buffer32.begin(), buffer32.end(), 0xDEADBEEF);
        // (a group moves onto copies of one point, which the builder's copy tolerance, 1e-6 of
        // the diagonal, may have joined: they stay that close)
        for (const auto& [position, group] : copies) {
            if (group.size() < 2) continue;
            uint32_t first = group[0];
            while (first >= n) first = built.substitute[first];
            for (uint32_t v : group) {
                while (v >= n) v = built.substitute[v];
                INFO("coincident copies separated at resolution " << n);
                double d2 = 0;
                for (int k = 0; k < 3; ++k) d2 += std::pow(double(built.positions[3 * v + k]) - built.positions[3 * first + k], 2);
                REQUIRE(std::sqrt(d2) <= 1e-5 * diagonal);
            }
        }
        // no cracks: welding by position, the level has no more border edges than the input
        const Topology topo = topology(built.positions.data(), expect.data(), count, true);
        REQUIRE(topo.border_edges <= full_topo.border_edges);
        if (input.closed_manifold) REQUIRE(topo.border_edges == 0);
        if (input.closed_manifold && (topology_kept || uint64_t(count) * 10 >= m.triangle_count)) {
            REQUIRE(topo.nonmanifold_edges == 0);
            // each piece keeps its Euler characteristic while it has triangles (a small piece
            // may vanish whole, pruned)
            std::set<uint32_t> present;
            for (const uint32_t c : expect) present.insert(pieces.of[built.original_index[c]]);
            int euler = 0;
            for (const uint32_t piece : present) euler += pieces.euler[piece];
            REQUIRE(topo.euler() == euler);
            if (n == N) REQUIRE(euler == input.euler);
        }
    }
    REQUIRE(tom::active_triangle_count(m, N) == m.triangle_count);

    // replay every substitution in order (N-1 down to s): none may flip a surviving triangle,
    // judged at each resolution a reader may use (a group of substitutions, copies of a point or
    // a pruned piece, is one step: its normals are compared before and after it)
    std::vector<std::vector<uint32_t>> around(N);
    std::map<uint32_t, std::array<float, 3>> group_before;  // triangles the current group changed: their normal before it
    std::vector<uint32_t> current(built.triangles);
    std::vector<uint8_t> dead(m.triangle_count, 0);
    for (uint32_t t = 0; t < m.triangle_count; ++t)
        for (int k = 0; k < 3; ++k) around[current[3 * t + k]].push_back(t);
    const float* p = built.positions.data();
    size_t flips = 0;
    for (uint32_t v = N; v-- > s;) {
        const uint32_t u = built.substitute[v];
        for (uint32_t t : around[v]) {
            if (dead[t]) continue;
            uint32_t* c = &current[3 * t];
            if (c[0] == u || c[1] == u || c[2] == u) {
                dead[t] = 1;
                continue;
            }
            group_before.emplace(t, normal_of(p, c[0], c[1], c[2]));
            for (int k = 0; k < 3; ++k)
                if (c[k] == v) c[k] = u;
            around[u].push_back(t);
        }
        if (m.splits_pair(v)) continue;  // the group goes on below v
        for (const auto& [t, before] : group_before) {
            if (dead[t]) continue;
            const uint32_t* c = &current[3 * t];
            const auto after = normal_of(p, c[0], c[1], c[2]);
            if (dot3(before, before) > 0 && dot3(before, after) <= 0) ++flips;
        }
        group_before.clear();
    }
    INFO("triangles flipped by a substitution");
    REQUIRE(flips == 0);
}

} // namespace test
