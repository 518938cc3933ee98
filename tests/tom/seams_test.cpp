// Meshes written as exporters and generators write them (Blender's glTF export, three.js'
// SphereGeometry, CylinderGeometry, CapsuleGeometry, TorusGeometry): a texture seam column of
// copies, poles and cap centres as fans of per-segment copies, hard edges as copies with other
// normals, and the seam's copies either exact or differing in the last bits, as a generator's
// sin(2 pi) makes them. Every level, welded by position, must stay closed.

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

#include "support.h"
#include "tom/builder/builder.h"
#include "tom/builder/mesh.h"
#include "tom/builder/refit.h"
#include "tom/extract.h"
#include "tom/io/import.h"
#include "tom/metrics/distance.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

// A point of a lathe's profile: radius, height, the normal's radial and height components, and
// the texture coordinate v.
struct ProfilePoint {
    double r, z, nr, nz, v;
};

// The profile revolved about z in `segments` steps, written the exporters' way: each ring has
// segments + 1 columns, the last at u = 1 a copy of the first (computed from the angle 2 pi when
// `last_bit`, so its position differs in the last bits, else copied exactly); a ring of radius 0
// is a fan of `segments` copies of its point, one per triangle, at u = (j + 1/2) / segments; two
// profile points at one place are a hard edge (copies with their own normals, no band between).
tom::Mesh lathe(const std::vector<ProfilePoint>& profile, uint32_t segments, bool last_bit, const char* name) {
    tom::Mesh m;
    m.name = name;
    std::vector<uint32_t> ring_start;
    for (const ProfilePoint& p : profile) {
        ring_start.push_back(m.vertex_count());
        const bool pole = p.r == 0;
        const uint32_t columns = pole ? segments : segments + 1;
        for (uint32_t j = 0; j < columns; ++j) {
            const double u = pole ? (j + 0.5) / segments : double(j) / segments;
            const double angle = 2 * kPi * (j == segments && !last_bit ? 0.0 : double(j) / segments);
            const double c = std::cos(angle), s = std::sin(angle);
            m.positions.insert(m.positions.end(), {float(p.r * c), float(p.r * s), float(p.z)});
            m.normals.insert(m.normals.end(), {float(p.nr * c), float(p.nr * s), float(p.nz)});
            m.texcoords.insert(m.texcoords.end(), {float(u), float(p.v)});
        }
    }
    for (size_t k = 0; k + 1 < profile.size(); ++k) {
        const ProfilePoint &a = profile[k], &b = profile[k + 1];
        if (a.r == b.r && a.z == b.z) continue;  // a hard edge: no band
        for (uint32_t j = 0; j < segments; ++j) {
            const uint32_t A = ring_start[k] + j, D = ring_start[k] + j + 1;
            const uint32_t B = ring_start[k + 1] + j, C = ring_start[k + 1] + j + 1;
            if (a.r == 0) {
                m.indices.insert(m.indices.end(), {A, B, C});  // the upper fan: A is the pole's copy j
            } else if (b.r == 0) {
                m.indices.insert(m.indices.end(), {A, B, D});  // the lower fan: B is the pole's copy j
            } else {
                m.indices.insert(m.indices.end(), {A, B, C});
                m.indices.insert(m.indices.end(), {A, C, D});
            }
        }
    }
    return m;
}

// A UV sphere of `rings` bands from pole to pole (three.js' SphereGeometry, Blender's UV sphere).
tom::Mesh uv_sphere(uint32_t rings, uint32_t segments, bool last_bit) {
    std::vector<ProfilePoint> profile;
    for (uint32_t i = 0; i <= rings; ++i) {
        const double phi = kPi * i / rings;
        const double r = i == 0 || i == rings ? 0.0 : std::sin(phi), z = std::cos(phi);
        profile.push_back({r, z, r, z, 1.0 - double(i) / rings});
    }
    return lathe(profile, segments, last_bit, last_bit ? "uv sphere, last-bit seam" : "uv sphere, exact seam");
}

// A capsule: two hemispheres joined by a cylinder of height 2 (three.js' CapsuleGeometry).
tom::Mesh capsule(uint32_t cap_rings, uint32_t segments, bool last_bit) {
    std::vector<ProfilePoint> profile;
    const uint32_t rows = 2 * cap_rings + 1;
    uint32_t row = 0;
    for (int half = 0; half < 2; ++half)
        for (uint32_t i = 0; i <= cap_rings; ++i, ++row) {
            const double phi = kPi / 2 * (half == 0 ? double(i) / cap_rings : 1.0 + double(i) / cap_rings);
            const double r = (half == 0 && i == 0) || (half == 1 && i == cap_rings) ? 0.0 : std::sin(phi), nz = std::cos(phi);
            profile.push_back({r, nz + (half == 0 ? 1.0 : -1.0), r, nz, 1.0 - double(row) / rows});
        }
    return lathe(profile, segments, last_bit, "capsule");
}

// A cylinder of radius 1 and height 2 with caps (three.js' CylinderGeometry): the side's rims and
// the caps' rims are copies with other normals (hard edges), each cap's centre a fan of copies.
tom::Mesh capped_cylinder(uint32_t height_rings, uint32_t segments, bool last_bit) {
    std::vector<ProfilePoint> profile{{0, 1, 0, 1, 1}, {1, 1, 0, 1, 1}};
    for (uint32_t i = 0; i <= height_rings; ++i) {
        const double z = 1.0 - 2.0 * i / height_rings;
        profile.push_back({1, z, 1, 0, 1.0 - double(i) / height_rings});
    }
    profile.push_back({1, -1, 0, -1, 0});
    profile.push_back({0, -1, 0, -1, 0});
    return lathe(profile, segments, last_bit, "capped cylinder");
}

// A torus (three.js' TorusGeometry): a seam column and a seam ring, both rows of copies.
tom::Mesh torus(uint32_t tube_segments, uint32_t segments, bool last_bit) {
    std::vector<ProfilePoint> profile;
    for (uint32_t i = 0; i <= tube_segments; ++i) {
        const double a = 2 * kPi * (i == tube_segments && !last_bit ? 0.0 : double(i) / tube_segments);
        profile.push_back({1.0 + 0.35 * std::cos(a), 0.35 * std::sin(a), std::cos(a), std::sin(a), double(i) / tube_segments});
    }
    tom::Mesh m = lathe(profile, segments, last_bit, "torus");
    return m;
}

// A triangle list welded by position within 1e-5 (the seam's last-bit copies meet): its open
// edges (an edge's uses one way less its uses the other) and its Euler characteristic.
struct Welded {
    int open = 0, euler = 0;
};
Welded weld(const float* positions, const uint32_t* indices, size_t triangle_count) {
    std::map<std::tuple<long, long, long>, uint32_t> points;
    auto point = [&](uint32_t v) {
        const auto key = std::make_tuple(std::lround(positions[3 * v] * 1e5), std::lround(positions[3 * v + 1] * 1e5), std::lround(positions[3 * v + 2] * 1e5));
        return points.emplace(key, uint32_t(points.size())).first->second;
    };
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < triangle_count; ++t)
        for (int k = 0; k < 3; ++k) ++directed[{point(indices[3 * t + k]), point(indices[3 * t + (k + 1) % 3])}];
    Welded w;
    int edges2 = 0;  // each undirected edge counted from both directions
    for (const auto& [edge, count] : directed) {
        const auto reverse = directed.find({edge.second, edge.first});
        w.open += std::abs(count - (reverse == directed.end() ? 0 : reverse->second));
        edges2 += reverse == directed.end() ? 2 : 1;
    }
    std::map<uint32_t, int> used;
    for (size_t c = 0; c < 3 * triangle_count; ++c) used[point(indices[c])] = 1;
    w.euler = int(used.size()) - edges2 / 2 + int(triangle_count);
    return w;
}

struct Level {
    uint32_t vertices, triangles;
    Welded welded;
};

// The open edges of the levels at 50%, 25%, 10%, 5% of the triangles and of the coarsest.
std::vector<Level> levels(const tom::TomMesh& built) {
    const tom::MeshView m = built.view();
    std::vector<uint32_t> buffer(built.triangles.size());
    std::vector<Level> out;
    for (double share : {1.0, 0.5, 0.25, 0.1, 0.05, 0.0}) {
        const uint32_t n = share > 0 ? tom::vertex_count_for_triangles(m, uint32_t(share * m.triangle_count)) : m.min_vertex_count;
        const tom::Extracted e = tom::extract(m, n, buffer.data(), buffer.size());
        out.push_back({e.vertex_count, e.triangle_count, weld(built.positions.data(), buffer.data(), e.triangle_count)});
    }
    return out;
}

} // namespace

TEST_CASE("exporter-written spheres, capsules, capped cylinders and tori never crack at seams and poles", "[builder][seams]") {
    for (const bool last_bit : {false, true}) {
        for (tom::Mesh mesh : {uv_sphere(96, 192, last_bit), capsule(24, 64, last_bit), capped_cylinder(8, 64, last_bit), torus(32, 64, last_bit)}) {
            INFO(mesh.name << (last_bit ? " (last-bit copies)" : " (exact copies)"));
            tom::clean_mesh(mesh);
            const uint32_t triangles = mesh.triangle_count();
            const Welded input = weld(mesh.positions.data(), mesh.indices.data(), triangles);
            REQUIRE(input.open == 0);  // closed as written
            tom::BuildStats stats;
            const tom::TomMesh built = tom::build(mesh, {}, &stats);
            CHECK(stats.seam_vertices > 0);
            const std::vector<Level> all = levels(built);
            for (const Level& level : all) {
                INFO(level.vertices << " vertices, " << level.triangles << " triangles");
                CHECK(level.welded.open == 0);
                // no handle closed, no sphere pinched, but at the coarsest level, where a join
                // may be all that is left (the torus ends as a double-sided triangle)
                if (&level != &all.back()) CHECK(level.welded.euler == input.euler);
            }
            // the seams and poles do not hold the floor up
            const uint32_t floor = tom::active_triangle_count(built.view(), built.min_vertex_count);
            INFO("coarsest " << floor << " of " << triangles << " triangles");
            CHECK(floor <= triangles / 20);
        }
    }
}

namespace {

// Every triangle with its own three vertices, as an unindexed file stores it; with face normals
// (flat shading) when `flat`, else without normals.
tom::Mesh unindexed(const tom::Mesh& m, bool flat) {
    tom::Mesh out;
    out.name = m.name + (flat ? ", flat-shaded" : ", unindexed");
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        const float* p[3];
        for (int k = 0; k < 3; ++k) p[k] = &m.positions[3 * size_t(m.indices[3 * t + k])];
        const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]}, e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; ++k) {
            out.positions.insert(out.positions.end(), p[k], p[k] + 3);
            if (flat) out.normals.insert(out.normals.end(), {float(n[0] / len), float(n[1] / len), float(n[2] / len)});
            out.indices.push_back(3 * t + uint32_t(k));
        }
    }
    return out;
}

tom::Surface surface_of(const tom::Mesh& m) { return {m.positions.data(), m.vertex_count(), m.indices.data(), m.triangle_count()}; }

// The two-sided mean distance (the larger direction's, per diagonal) of `built` at `triangles`
// against `original`, and the level's share of folded edges: interior edges whose two triangles
// face nearly opposite ways (dihedral turn above 150 degrees), a wedge or a sheet.
struct Quality {
    uint32_t triangles;
    double mean, folded;
};
Quality quality(const tom::Mesh& original, const tom::TomMesh& built, uint32_t triangles) {
    const tom::MeshView m = built.view();
    std::vector<uint32_t> idx(built.triangles.size());
    const tom::Extracted e = tom::extract(m, tom::vertex_count_within_triangles(m, triangles), idx.data(), idx.size());
    const tom::Distance d = tom::metro_distance(surface_of(original), {built.positions.data(), e.vertex_count, idx.data(), e.triangle_count});
    const std::vector<float> points = test::snap_copies(built.positions.data(), e.vertex_count);
    std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, std::array<double, 3>> first_normal;
    size_t edges = 0, folded = 0;
    for (uint32_t t = 0; t < e.triangle_count; ++t) {
        std::array<float, 3> c[3];
        for (int k = 0; k < 3; ++k) std::copy_n(&points[3 * size_t(idx[3 * t + k])], 3, c[k].data());
        const double e1[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]}, e2[3] = {c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]};
        std::array<double, 3> n = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len == 0) continue;
        for (double& x : n) x /= len;
        for (int k = 0; k < 3; ++k) {
            const auto key = std::minmax(c[k], c[(k + 1) % 3]);
            const auto [it, fresh] = first_normal.emplace(std::make_pair(key.first, key.second), n);
            if (fresh) continue;
            ++edges;
            folded += n[0] * it->second[0] + n[1] * it->second[1] + n[2] * it->second[2] < std::cos(150.0 * kPi / 180.0);
        }
    }
    return {e.triangle_count, std::max(d.forward.mean, d.backward.mean) / d.diagonal, edges ? double(folded) / double(edges) : 0.0};
}

} // namespace

TEST_CASE("unindexed and flat-shaded copies of real meshes simplify as far and as well as the indexed mesh", "[builder][seams][samples]") {
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.name.find("fandisk") == std::string::npos && nm.name.find("cow") == std::string::npos) continue;
        const tom::Mesh& indexed = nm.mesh;
        const tom::TomMesh reference = tom::build(indexed);
        // welded on import, an unindexed file is the indexed mesh again
        tom::Mesh welded = unindexed(indexed, false);
        const tom::CleanStats clean = tom::clean_mesh(welded);
        CHECK(welded.vertex_count() == indexed.vertex_count());
        CHECK(clean.welded_vertices == 3 * indexed.triangle_count() - indexed.vertex_count());
        for (const bool flat : {false, true}) {
            // kept as written (--no-weld, or flat normals a weld cannot merge): every vertex a copy
            tom::Mesh copies = unindexed(indexed, flat);
            tom::clean_mesh(copies, {false});
            INFO(copies.name);
            tom::BuildStats stats;
            const tom::TomMesh built = tom::build(copies, {}, &stats);
            CHECK(stats.seam_vertices == copies.vertex_count());
            const uint32_t floor = tom::active_triangle_count(built.view(), built.min_vertex_count);
            CHECK(floor <= std::max<uint32_t>(16, indexed.triangle_count() / 100));
            for (const double share : {0.25, 0.1, 0.02}) {
                const uint32_t target = uint32_t(share * indexed.triangle_count());
                const Quality q = quality(indexed, built, target), r = quality(indexed, reference, target);
                INFO(share * 100 << "%: " << q.triangles << " triangles, mean " << q.mean << " (indexed " << r.mean << "), folded edges " << q.folded
                                 << " (indexed " << r.folded << ")");
                CHECK(q.triangles >= 0.9 * target);
                CHECK(q.mean <= 1.5 * r.mean);
                CHECK(q.folded <= r.folded + 0.01);
            }
        }
    }
}

TEST_CASE("a building's small pieces vanish whole instead of holding the floor up", "[builder][seams][samples]") {
    // assimp's regr01.obj: a house of 111 boxes and slabs (walls, planks, rafters), each closed
    // box stuck at its 12 triangles, since every substitution would turn a face by 90 degrees or more
    tom::ImportResult r = tom::import_file(test::sample("assimp/OBJ/regr01.obj"));
    REQUIRE(r.meshes.size() == 1);
    tom::Mesh& mesh = r.meshes[0];
    tom::clean_mesh(mesh);
    tom::BuildStats stats;
    const tom::TomMesh built = tom::build(mesh, {}, &stats);
    const uint32_t floor = tom::active_triangle_count(built.view(), built.min_vertex_count);
    INFO(stats.pruned_pieces << " pieces pruned; coarsest " << floor << " of " << mesh.triangle_count() << " triangles");
    CHECK(stats.pruned_pieces >= 20);  // measured 31 (the largest pieces stay, simplified)
    CHECK(floor <= mesh.triangle_count() / 4);
    // a move pays for all the surface it displaces (summed quadric errors): at half its triangles
    // the house keeps its roof and slabs, 0.035% of the diagonal where averaged errors, ranking
    // the roof's corner with a plank's, left 0.053% (half the roof gone)
    tom::BuildParams untextured;  // as tombuild builds it: no material samples its coordinates
    untextured.weigh_texcoords = false;
    const Quality half = quality(mesh, tom::build(mesh, untextured), mesh.triangle_count() / 2);
    INFO("at " << half.triangles << " triangles: mean " << half.mean * 100 << "% of the diagonal");
    CHECK(half.mean < 0.00045);
    // no triangle flipped (a pruned piece's substitutions are one group, judged together), no
    // new open edge, and the rest of every build's invariants
    test::check_invariants({"regr01", mesh, false, 0}, built);
}

TEST_CASE("a building's walls flatten into sheets before its roof folds: joins ranked behind manifold moves", "[builder][seams][samples]") {
    // regr01's walls, floors and planks are thin closed boxes; keeping every box a closed
    // manifold (the link condition) left only the roof's corners to move once the planks were
    // gone, and at 25% of its triangles the roof lay folded onto its gables. Joining a box's two
    // faces is legal, ranked at 8 times its cost.
    tom::ImportResult r = tom::import_file(test::sample("assimp/OBJ/regr01.obj"));
    tom::Mesh& mesh = r.meshes.at(0);
    tom::clean_mesh(mesh);
    tom::BuildParams joined, kept;
    joined.weigh_texcoords = kept.weigh_texcoords = false;  // as tombuild builds it: no material samples them
    kept.keep_topology = true;
    const uint32_t quarter = mesh.triangle_count() / 4;
    const Quality j = quality(mesh, tom::build(mesh, joined), quarter), k = quality(mesh, tom::build(mesh, kept), quarter);
    INFO("at " << quarter << " triangles: mean " << j.mean * 100 << "% of the diagonal joining sheets, " << k.mean * 100 << "% keeping the topology");
    CHECK(j.mean < 0.001);
    CHECK(j.mean * 3 < k.mean);
    // (its share of folded edges rises: a flattened wall is a double-sided sheet)
}

TEST_CASE("joins come only where the manifold moves run out: a scanned mesh's levels are those keeping its topology", "[builder][samples]") {
    // bunny00 is a closed manifold whose every substitution down to its last hundred vertices
    // is manifold at 8 times a join's cost: both builds remove the same vertices in the same
    // order until then (the TOM order lists removed vertices from the last to the first)
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.name.find("bunny") == std::string::npos) continue;
        tom::BuildParams kept;
        kept.keep_topology = true;
        const tom::TomMesh a = tom::build(nm.mesh), b = tom::build(nm.mesh, kept);
        const uint32_t n = a.view().vertex_count, common = n - 100;
        uint32_t same = 0;
        while (same < common && a.original_index[n - 1 - same] == b.original_index[n - 1 - same] &&
               a.original_index[a.substitute[n - 1 - same]] == b.original_index[b.substitute[n - 1 - same]])
            ++same;
        INFO(nm.name << ": the first " << same << " of " << n << " substitutions agree");
        CHECK(same == common);
    }
}

TEST_CASE("parts meeting along an edge move along it: a wall standing on a floor", "[builder][seams]") {
    // a floor (20 x 20 quads) and a wall (20 x 10) standing across its middle, sharing the 21
    // vertices of their junction: its edges have three triangles (non-manifold), once locking all
    // 21; each inner one has two such edges, a chain, and moves along it as a border vertex does
    tom::Mesh mesh;
    mesh.name = "wall on a floor";
    auto vertex = [&](float x, float y, float z) {
        mesh.positions.insert(mesh.positions.end(), {x, y, z});
        return uint32_t(mesh.vertex_count() - 1);
    };
    auto grid = [&](uint32_t nu, uint32_t nv, auto&& at) {  // at(i, j) -> vertex
        for (uint32_t j = 0; j < nv; ++j)
            for (uint32_t i = 0; i < nu; ++i) {
                const uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
                mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
            }
    };
    std::vector<uint32_t> floor(21 * 21), wall(21 * 11);
    for (uint32_t j = 0; j <= 20; ++j)
        for (uint32_t i = 0; i <= 20; ++i) floor[j * 21 + i] = vertex(i / 20.0f, j / 20.0f, 0.0f);
    for (uint32_t j = 0; j <= 10; ++j)
        for (uint32_t i = 0; i <= 20; ++i) wall[j * 21 + i] = j == 0 ? floor[10 * 21 + i] : vertex(i / 20.0f, 0.5f, j / 20.0f);
    grid(20, 20, [&](uint32_t i, uint32_t j) { return floor[j * 21 + i]; });
    grid(20, 10, [&](uint32_t i, uint32_t j) { return wall[j * 21 + i]; });
    tom::BuildStats stats;
    const tom::TomMesh built = tom::build(mesh, {}, &stats);
    // the coarsest level keeps the junction's two ends and the floor's and wall's corners
    uint32_t on_junction = 0;
    for (uint32_t v = 0; v < built.min_vertex_count; ++v)
        on_junction += built.positions[3 * v + 1] == 0.5f && built.positions[3 * v + 2] == 0.0f;
    INFO(stats.locked_vertices << " locked; the coarsest level keeps " << on_junction << " junction vertices of " << built.min_vertex_count);
    CHECK(stats.locked_vertices <= 2);
    CHECK(on_junction <= 3);
    test::check_invariants({mesh.name, mesh, false, 0}, built);  // no crack opens between the parts
}

namespace {

// A hemisphere from its pole to its equator: an open edge all around.
tom::Mesh hemisphere(uint32_t rings, uint32_t segments) {
    std::vector<ProfilePoint> profile;
    for (uint32_t i = 0; i <= rings; ++i) {
        const double phi = 0.5 * kPi * i / rings;
        const double r = i == 0 ? 0.0 : std::sin(phi), z = std::cos(phi);
        profile.push_back({r, z, r, z, 1.0 - double(i) / rings});
    }
    return lathe(profile, segments, false, "hemisphere");
}

// The largest turn, in degrees, of a level's triangles from their plain positions to re-fitted ones.
double largest_turn(const float* plain, const float* refit, const std::vector<uint32_t>& idx, uint32_t triangles) {
    double worst = 0;
    for (uint32_t t = 0; t < triangles; ++t) {
        auto normal = [&](const float* x) {
            const float* p[3] = {x + 3 * size_t(idx[3 * t]), x + 3 * size_t(idx[3 * t + 1]), x + 3 * size_t(idx[3 * t + 2])};
            const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]}, e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
            return std::array<double, 3>{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        };
        const std::array<double, 3> a = normal(plain), b = normal(refit);
        const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        if (la == 0 || lb == 0) continue;
        worst = std::max(worst, std::acos(std::clamp((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb), -1.0, 1.0)) * 180.0 / kPi);
    }
    return worst;
}

// How much closer to the original a re-fitted level is than the plain one, at most: its Metro
// mean, its normals' mean deviation (degrees, plus a thousandth of a degree: a smooth level's
// plain normals are exact to a few thousandths) and its texture coordinates'.
struct Gains {
    double mean, normals, uv;
};

// One mesh's levels at 50%, 25% and 10%, plain and re-fitted: the re-fitted level closer to the
// original by the `gains`, as closed (welded by position) and of the same Euler number, no
// triangle turned by more than 78 degrees, vertices past the level untouched, normals of unit
// length.
void check_refit(const tom::Mesh& original, const tom::TomMesh& built, Gains gains) {
    const tom::MeshView m = built.view();
    const auto stream = [](const std::vector<float>& values) { return values.empty() ? nullptr : values.data(); };
    const tom::MetroReference reference(surface_of(original), {}, {stream(original.normals), stream(original.texcoords)});
    std::vector<uint32_t> idx(built.triangles.size());
    for (double share : {0.5, 0.25, 0.1}) {
        const uint32_t n = tom::vertex_count_for_triangles(m, uint32_t(share * m.triangle_count));
        const tom::Extracted e = tom::extract(m, n, idx.data(), idx.size());
        const tom::RefitLevel r = tom::refit_level(m, n);
        INFO(original.name << " at " << e.triangle_count << " triangles: " << r.stats.moved << " points moved, " << r.stats.fixed << " fixed, " << r.stats.kept
                           << " kept, " << r.stats.reverted << " put back");
        const tom::Distance plain = tom::metro_distance(surface_of(original), {built.positions.data(), e.vertex_count, idx.data(), e.triangle_count});
        const tom::Distance refit = tom::metro_distance(surface_of(original), {r.positions.data(), e.vertex_count, idx.data(), e.triangle_count});
        const double plain_mean = std::max(plain.forward.mean, plain.backward.mean), refit_mean = std::max(refit.forward.mean, refit.backward.mean);
        INFO("Metro mean " << plain_mean / plain.diagonal << " plain, " << refit_mean / refit.diagonal << " re-fitted");
        CHECK(r.stats.moved > 0);
        CHECK(refit_mean <= gains.mean * plain_mean + 1e-9 * plain.diagonal);  // a level that is exact (a flat cap) stays exact
        tom::AttributeDeviation plain_attributes, refit_attributes;
        reference.compare({built.positions.data(), e.vertex_count, idx.data(), e.triangle_count}, {stream(built.normals), stream(built.texcoords)},
                          plain_attributes);
        reference.compare({r.positions.data(), e.vertex_count, idx.data(), e.triangle_count}, {stream(r.normals), stream(r.texcoords)}, refit_attributes);
        INFO("normals " << plain_attributes.normal_mean_degrees << " degrees plain, " << refit_attributes.normal_mean_degrees
                        << " re-fitted; texture coordinates " << plain_attributes.uv_mean << " plain, " << refit_attributes.uv_mean << " re-fitted");
        CHECK(refit_attributes.normals == !built.normals.empty());
        CHECK(refit_attributes.normal_mean_degrees <= gains.normals * plain_attributes.normal_mean_degrees + 1e-3);
        CHECK(refit_attributes.uv_mean <= gains.uv * plain_attributes.uv_mean + 1e-6);  // (an exact level's are exact to float rounding)
        const Welded before = weld(built.positions.data(), idx.data(), e.triangle_count), after = weld(r.positions.data(), idx.data(), e.triangle_count);
        CHECK(after.open == before.open);
        CHECK(after.euler == before.euler);
        CHECK(largest_turn(built.positions.data(), r.positions.data(), idx, e.triangle_count) <= 78.5);
        CHECK(std::equal(r.positions.begin() + 3 * ptrdiff_t(n), r.positions.end(), built.positions.begin() + 3 * ptrdiff_t(n)));
        if (!built.normals.empty()) {
            REQUIRE(r.normals.size() == built.normals.size());
            double worst = 0;
            for (uint32_t v = 0; v < n; ++v) {
                const float* x = &r.normals[3 * size_t(v)];
                worst = std::max(worst, std::abs(std::sqrt(double(x[0]) * x[0] + double(x[1]) * x[1] + double(x[2]) * x[2]) - 1.0));
            }
            CHECK(worst < 1e-5);
        }
    }
}

} // namespace

// The mean distance, over the level's vertices away from the poles (whose fans interpolate u
// across all angles), between a sphere's texture coordinates and those its position on the
// sphere gives (u = angle / 2 pi, modulo 1 across the seam; v = 1 - polar angle / pi): how far
// the texture slides where vertices moved.
double texture_slide(const float* positions, const float* uv, uint32_t n) {
    double sum = 0;
    uint32_t count = 0;
    for (uint32_t v = 0; v < n; ++v) {
        const double x = positions[3 * v], y = positions[3 * v + 1], z = positions[3 * v + 2];
        const double r = std::sqrt(x * x + y * y + z * z);
        if (std::abs(z) > 0.9 * r) continue;
        const double du = std::abs(uv[2 * v] - std::atan2(y, x) / (2 * kPi)), dv = uv[2 * v + 1] - (1 - std::acos(z / r) / kPi);
        const double ud = std::min({du, std::abs(du - 1), std::abs(du - 2)});
        sum += std::sqrt(ud * ud + dv * dv), ++count;
    }
    return count ? sum / count : 0.0;
}

TEST_CASE("a level re-fitted to be written on its own is closer to the surface and as closed", "[builder][seams][refit]") {
    // a moved vertex takes the texture coordinates the surface has where it now stands: on a
    // UV sphere they stay those of its place on the sphere (a vertex keeping its own slides by
    // as much as it moved along the surface)
    for (const bool last_bit : {false, true}) {
        tom::Mesh sphere = uv_sphere(48, 96, last_bit);
        tom::clean_mesh(sphere);
        const tom::TomMesh built = tom::build(sphere);
        const tom::MeshView m = built.view();
        for (double share : {0.25, 0.1}) {
            const uint32_t n = m.whole_groups_below(tom::vertex_count_for_triangles(m, uint32_t(share * m.triangle_count)));
            const tom::RefitLevel r = tom::refit_level(m, n);
            REQUIRE(r.texcoords.size() == 2 * size_t(m.vertex_count));
            const double plain = texture_slide(built.positions.data(), built.texcoords.data(), n);
            const double kept = texture_slide(r.positions.data(), built.texcoords.data(), n), resampled = texture_slide(r.positions.data(), r.texcoords.data(), n);
            INFO(sphere.name << " at " << n << " vertices: slide " << plain << " plain, " << kept << " with its own, " << resampled << " resampled");
            CHECK(resampled < 0.1 * kept);
        }
    }

    // spheres, capped cylinders (hard edges at the rims) and tori as exporters write them: the
    // copies along seams, poles and hard edges move as one. A capped cylinder's coarsest level
    // cuts its rims short, so that the metric pairs samples of a side with the cap's triangles
    // (another chart of texture coordinates), which no fit of each side to its own surface mends:
    // there its texture coordinates only stay near the plain level's. (Its 50% is exact.)
    for (const bool last_bit : {false, true}) {
        tom::Mesh sphere = uv_sphere(48, 96, last_bit), cylinder = capped_cylinder(8, 64, last_bit), ring = torus(32, 64, last_bit);
        for (tom::Mesh* mesh : {&sphere, &cylinder, &ring}) tom::clean_mesh(*mesh);
        check_refit(sphere, tom::build(sphere), {0.65, 0.9, 0.75});
        check_refit(cylinder, tom::build(cylinder), {0.8, 0.97, 1.2});
        check_refit(ring, tom::build(ring), {0.8, 0.65, 0.6});
    }
    // an open edge keeps its place: the level's outline is the original's
    tom::Mesh open = hemisphere(24, 96);
    tom::clean_mesh(open);
    const tom::TomMesh built = tom::build(open);
    check_refit(open, built, {0.7, 0.85, 0.75});
    const tom::MeshView m = built.view();
    const uint32_t n = tom::vertex_count_for_triangles(m, m.triangle_count / 10);
    const tom::RefitLevel r = tom::refit_level(m, n);
    uint32_t on_rim = 0;
    for (uint32_t v = 0; v < n; ++v) {
        if (std::abs(built.positions[3 * size_t(v) + 2]) > 1e-6f) continue;  // the rim lies at z = 0
        ++on_rim;
        CHECK(std::equal(&r.positions[3 * size_t(v)], &r.positions[3 * size_t(v)] + 3, &built.positions[3 * size_t(v)]));
    }
    CHECK(on_rim >= 8);
    CHECK(r.stats.fixed >= on_rim / 2);  // copies at the seam count once
    // resolutions are taken as extract() takes them: below the coarsest, or among a group's copies
    const tom::RefitLevel coarsest = tom::refit_level(m, 0);
    CHECK(coarsest.positions == tom::refit_level(m, m.min_vertex_count).positions);
    uint32_t split = m.min_vertex_count + 1;
    while (split < m.vertex_count && !m.splits_pair(split)) ++split;
    REQUIRE(split < m.vertex_count);
    CHECK(tom::refit_level(m, split).positions == tom::refit_level(m, m.whole_groups_below(split)).positions);
}

TEST_CASE("re-fitted levels of real meshes are closer to them", "[builder][refit][samples]") {
    for (const test::NamedMesh& nm : test::real_meshes()) {
        if (nm.name.find("bunny00") == std::string::npos && nm.name.find("cow") == std::string::npos) continue;
        check_refit(nm.mesh, tom::build(nm.mesh), {0.85, 0.8, 1.0});
    }
}
