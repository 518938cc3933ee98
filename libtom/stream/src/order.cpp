// A .tom's vertices renumbered for streaming (docs/FORMAT.md, "Streamed files"): within each
// chunk, the splits ordered by their substitutes, so that the splits block codes each substitute
// as a small difference from the one before instead of in index_bits(v) bits. The levels at the
// chunk boundaries are the same meshes; the resolutions inside a chunk take its splits in that
// order instead of the builder's.

#include <algorithm>
#include <cstring>
#include <numeric>
#include <queue>

#include "format_layout.h"
#include "scene_codec.h"
#include "stream_order.h"
#include "tom/errors.h"

namespace tom {

namespace {

/// A group of copies (or a single vertex), [first, end): its members move together.
struct Unit {
    uint32_t first = 0, end = 0;
    uint32_t waiting = 0;  // members whose substitute outside the unit is in the chunk, not yet placed
};

/// The units of vertices [a, b) of `m` (no group crosses a or b).
std::vector<Unit> units_of(const MeshView& m, uint32_t a, uint32_t b) {
    std::vector<Unit> units;
    for (uint32_t v = a; v < b;) {
        Unit u{v, v + 1, 0};
        while (u.end < b && m.splits_pair(u.end)) ++u.end;  // bit end - 1 set: end joins the group
        units.push_back(u);
        v = u.end;
    }
    return units;
}

/// Chunk [a, b)'s vertices numbered from a (those below a already are, in `to_new`): each unit
/// once its members' substitutes are numbered, the one whose largest new substitute outside it
/// is smallest first (then the lower first vertex). Every number given is past the ones before,
/// so a unit made ready by the one just placed never precedes it: the substitutes, in the new
/// numbering, ascend from split to split (but within a unit).
void number_chunk(const MeshView& m, uint32_t a, uint32_t b, std::vector<uint32_t>& to_new) {
    std::vector<Unit> units = units_of(m, a, b);
    std::vector<std::vector<uint32_t>> waiting_on(b - a);  // per vertex of the chunk: units waiting for it
    for (uint32_t i = 0; i < units.size(); ++i)
        for (uint32_t w = units[i].first; w < units[i].end; ++w) {
            const uint32_t p = m.substitute_at(w);
            if (p >= a && p < units[i].first) waiting_on[p - a].push_back(i), ++units[i].waiting;
        }
    using Ready = std::pair<uint32_t, uint32_t>;  // (key, unit)
    std::priority_queue<Ready, std::vector<Ready>, std::greater<Ready>> ready;
    auto make_ready = [&](uint32_t i) {
        uint32_t key = 0;
        for (uint32_t w = units[i].first; w < units[i].end; ++w)
            if (m.substitute_at(w) < units[i].first) key = std::max(key, to_new[m.substitute_at(w)]);
        ready.push({key, i});
    };
    for (uint32_t i = 0; i < units.size(); ++i)
        if (!units[i].waiting) make_ready(i);
    uint32_t next = a;
    while (!ready.empty()) {
        const Unit& u = units[ready.top().second];
        ready.pop();
        for (uint32_t w = u.first; w < u.end; ++w) to_new[w] = next++;
        for (uint32_t w = u.first; w < u.end; ++w)
            for (const uint32_t i : waiting_on[w - a])
                if (--units[i].waiting == 0) make_ready(i);
    }
    if (next != b) throw InternalError("stream order: a chunk's substitutes do not form a forest");
}

/// Vertices renumbered chunk by chunk (number_chunk); the survivors keep their numbers.
std::vector<uint32_t> renumbering(const MeshView& m, const std::vector<uint32_t>& ends) {
    std::vector<uint32_t> to_new(m.vertex_count);
    std::iota(to_new.begin(), to_new.begin() + std::min(m.min_vertex_count, m.vertex_count), 0u);
    uint32_t a = m.min_vertex_count;
    for (const uint32_t b : ends) {
        if (b <= a) continue;
        number_chunk(m, a, b, to_new);
        a = b;
    }
    return to_new;
}

/// The lowest resolution at which vertices x and y map to different vertices (at least S): their
/// substitution chains meet at some vertex; the images differ once the resolution passes the
/// lower of the two vertices each chain visits last before they meet.
uint32_t pair_birth(const std::vector<uint32_t>& substitute, uint32_t S, uint32_t x, uint32_t y) {
    uint32_t last_x = UINT32_MAX, last_y = UINT32_MAX;
    while (x != y) {
        if (std::max(x, y) < S) return S;  // two survivors: apart at every resolution
        if (x > y) {
            last_x = x, x = substitute[x];
        } else {
            last_y = y, y = substitute[y];
        }
    }
    return std::max(S, std::min(last_x, last_y) + 1);
}

/// The renumbered mesh's arrays.
struct Renumbered {
    std::vector<uint32_t> substitute, corners;
    std::vector<uint8_t> pair_bits;
};

/// Substitutes and corners in the new numbering, each part's triangles sorted again by the
/// resolution they become live at (stable: the order of triangles born together is kept).
Renumbered renumber_topology(const MeshView& m, const std::vector<uint32_t>& to_new) {
    const uint32_t V = m.vertex_count, S = m.min_vertex_count;
    Renumbered r;
    r.substitute.resize(V);
    for (uint32_t v = 0; v < V; ++v) r.substitute[to_new[v]] = to_new[m.substitute_at(v)];
    std::vector<uint32_t> corners(3 * size_t(m.triangle_count)), order, birth(m.triangle_count);
    for (size_t c = 0; c < corners.size(); ++c) corners[c] = to_new[m.corner(uint32_t(c))];
    for (uint32_t t = 0; t < m.triangle_count; ++t) {
        const uint32_t* c = &corners[3 * size_t(t)];
        birth[t] = std::max({pair_birth(r.substitute, S, c[0], c[1]), pair_birth(r.substitute, S, c[1], c[2]), pair_birth(r.substitute, S, c[0], c[2])});
    }
    r.corners.resize(corners.size());
    for (uint32_t q = 0; q < part_count(m); ++q) {
        const Part part = part_at(m, q);
        order.resize(part.triangle_count);
        std::iota(order.begin(), order.end(), part.first_triangle);
        std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return birth[x] < birth[y]; });
        for (uint32_t i = 0; i < part.triangle_count; ++i) std::copy_n(&corners[3 * size_t(order[i])], 3, &r.corners[3 * (size_t(part.first_triangle) + i)]);
    }
    if (m.pair_bits) {
        r.pair_bits.assign((size_t(V) + 7) / 8, 0);
        for (uint32_t v = 0; v + 1 < V; ++v)
            if (m.splits_pair(v + 1)) {  // v and v + 1 copies: adjacent in the new numbering too
                const uint32_t n = to_new[v];
                r.pair_bits[n / 8] |= uint8_t(1u << (n % 8));
            }
    }
    return r;
}

/// Elements of `size` bytes per vertex, moved to their new places.
std::vector<uint8_t> permuted(const uint8_t* data, size_t size, const std::vector<uint32_t>& to_new) {
    std::vector<uint8_t> out(to_new.size() * size);
    for (size_t v = 0; v < to_new.size(); ++v) std::memcpy(&out[to_new[v] * size], data + v * size, size);
    return out;
}

/// Mesh `index`'s sections in the new numbering, in place of the stored ones (`COAR`, an
/// extraction shortcut that depends on the order, is left out).
void renumber_sections(const File& file, const uint8_t* bytes, uint32_t index, const std::vector<uint32_t>& ends, std::vector<layout::PendingSection>& out) {
    using namespace layout;
    const MeshView& m = file.mesh(index);
    const std::vector<uint32_t> to_new = renumbering(m, ends);
    const Renumbered r = renumber_topology(m, to_new);
    for (const SectionInfo& s : file.sections()) {
        if (s.mesh != index) continue;
        const uint32_t type = fourcc(s.type);
        const uint8_t* data = bytes + s.offset;
        std::vector<uint8_t> section;
        if (type == sec_coarse) continue;
        if (type == sec_substitute) {
            section = index_bytes(r.substitute, m.index_size);
        } else if (type == sec_triangles) {
            section = index_bytes(r.corners, m.index_size);
        } else if (type == sec_pairs) {
            section = r.pair_bits;
        } else if (type == sec_extra_streams) {
            std::vector<std::vector<uint8_t>> storage;
            std::vector<VertexStreamView> streams(m.extra_streams, m.extra_streams + m.extra_stream_count);
            for (VertexStreamView& x : streams) {
                storage.push_back(permuted(x.data, x.components * component_bytes(x.component_type), to_new));
                x.data = storage.back().data();
            }
            section = detail::encode_extra_streams(streams, m.vertex_count);
        } else if (m.vertex_count && s.bytes % m.vertex_count == 0 &&
                   (type == sec_positions ||
                    std::any_of(std::begin(attribute_streams), std::end(attribute_streams), [&](const AttributeStream& a) { return a.section == type; }))) {
            section = permuted(data, s.bytes / m.vertex_count, to_new);
        } else {
            section.assign(data, data + s.bytes);
        }
        out.push_back({type, s.mesh, std::move(section)});
    }
}

}  // namespace

std::vector<uint8_t> stream_ordered_image(const File& file, const uint8_t* bytes, const std::vector<std::vector<uint32_t>>& ends) {
    std::vector<layout::PendingSection> sections;
    for (const SectionInfo& s : file.sections())
        if (s.mesh == layout::file_level)
            sections.push_back({layout::fourcc(s.type), s.mesh, std::vector<uint8_t>(bytes + s.offset, bytes + s.offset + s.bytes)});
    for (uint32_t i = 0; i < file.mesh_count(); ++i) renumber_sections(file, bytes, i, ends[i], sections);
    return layout::assemble_file(sections, file.mesh_count());
}

}  // namespace tom
