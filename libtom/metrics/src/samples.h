#pragma once
// The sample points of the Metro-style distance (metrics/distance_cgal.cpp): every vertex, points
// along every edge, stratified area-uniform points on the faces, sorted in Morton order; and the
// face samples of the attribute deviation. Internal to tom::metrics.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "parallel.h"
#include "geometry.h"
#include "tom/metrics/distance.h"

namespace tom::detail {

constexpr size_t kChunk = 4096;

// Runs work(chunk, begin, end) over [0, n) in chunks of kChunk on up to `threads` threads (0: every
// core); results kept per chunk and combined in chunk order give the same figures for any count.
template <class Work>
size_t parallel_chunks(size_t n, unsigned threads, Work&& work) {
    parallel_blocks(n, kChunk, threads, [&](unsigned, size_t begin, size_t end) { work(begin / kChunk, begin, end); });
    return (n + kChunk - 1) / kChunk;
}

inline V3 vertex(const Surface& s, uint32_t v) {
    return {s.positions[3 * size_t(v)], s.positions[3 * size_t(v) + 1], s.positions[3 * size_t(v) + 2]};
}
// corner k of triangle t
inline V3 corner(const Surface& s, size_t t, int k) { return vertex(s, s.indices[3 * t + size_t(k)]); }

double face_area(const Surface& s, size_t t);
double surface_area(const Surface& s);

struct Samples {
    std::vector<V3> points;
    std::vector<uint64_t> keys;  // per point: its Morton code; points are sorted by it
    std::vector<uint32_t> faces; // per point: a face it lies on (a vertex's or an edge's: one of theirs)
    double extent = 0;           // the side of the Morton grid's cube
    uint64_t vertex = 0, edge = 0, face = 0;
    double area = 0;
};

// Morton codes of a 2^16-per-axis grid: 48-bit keys.
constexpr int kMortonBits = 16;

// Buffers order_morton() reuses from call to call (fresh ones of this size cost more in page
// faults than the sort itself).
struct MortonScratch {
    std::vector<std::pair<uint64_t, uint32_t>> keyed, other;  // (the edges')
    std::vector<uint64_t> packed, packed_other;              // (code, index) words
    std::vector<V3> sorted;
    std::vector<uint32_t> faces, order;  // sample_surface()'s faces in the order made, and the sort's permutation
};

// Sorts points in Morton order of a 2^16-per-axis grid over their bounding cube (over 65,536
// points, of a coarser one, 2^14 up to 4M points, and ties in the order given), so that the
// points of every octree cell are a contiguous range (measure() groups them by cell); keys get
// each point's code (as a 48-bit code, zeros where the grid is coarser), extent the cube's side;
// `permutation`, when given, the order applied (new position -> old). Deterministic; `threads`
// as parallel_chunks.
void order_morton(std::vector<V3>& points, std::vector<uint64_t>& keys, double& extent, MortonScratch& scratch, unsigned threads,
                  std::vector<uint32_t>* permutation = nullptr);

// Attribute samples: points of the faces kept as (face, barycentrics) too, so the attributes
// can be interpolated there.
struct FaceSample {
    uint32_t face;
    double u, v;  // weights of corners 1 and 2
};

// Face samples picked from a Samples for the attribute deviation: every `every`-th face sample
// in the order made (area-uniform as they are), as (face, barycentrics); of each point in
// Morton order, its index in `picked` or kNotPicked.
struct PickedFaceSamples {
    static constexpr uint32_t kNotPicked = 0xffffffffu;
    std::vector<FaceSample> picked;
    std::vector<uint32_t> of_point;
};

// Fills `out` (its buffers reused) with about `target` samples of s and, `with_faces`, the face
// of each (left empty otherwise: a search without hints does not read them); with `pick`, about
// `pick_count` of its face samples picked into it (and the faces kept).
void sample_surface(const Surface& s, uint64_t target, const DistanceParams& p, Samples& out, MortonScratch& scratch,
                    PickedFaceSamples* pick = nullptr, uint64_t pick_count = 0, bool with_faces = true);

// The faces of s in Morton order of their centroids, over the box of its corners (a 2^16 grid a
// side, coarser where the face index needs more than 16 of a word's 64 bits), ties by face;
// `threads` as parallel_chunks. (The compact tree's leaves and the sample batches' runs.)
std::vector<uint32_t> faces_in_morton_order(const Surface& s, unsigned threads);

// A surface's samples for one target count made a batch at a time, each about `batch_samples`
// points: the samples of a run of faces in Morton order of their centroids (a compact part of
// the surface, as the run search wants), each face with the vertices and edges it samples (the
// first face that has each, as sample_surface() assigns them). Together the batches hold the
// very points sample_surface() makes, in another order; and with `pick_count`, the same picks
// (every every-th face sample by its number among them). About 13 bytes a face, where a whole
// surface's samples take some 80 bytes a sample in flight.
class SampleBatches {
public:
    SampleBatches(const Surface& s, uint64_t target, const DistanceParams& p, uint64_t batch_samples, uint64_t pick_count = 0);
    size_t size() const { return cuts_.size() - 1; }
    /// Batch k into `out` in Morton order (its buffers reused), the face of each point when
    /// `with_faces`; with `pick`, the batch's picks (their numbers local to it) and of each point
    /// its pick or kNotPicked.
    void make(size_t k, Samples& out, MortonScratch& scratch, PickedFaceSamples* pick = nullptr, bool with_faces = false) const;
    uint64_t vertex = 0, edge = 0, face = 0, picked = 0;  ///< of all batches
    double area = 0;

private:
    uint64_t samples_of(uint32_t t) const;

    Surface s_;
    DistanceParams p_;
    double per_length_ = 0;
    uint64_t every_ = 0;             // the picking stride among the face samples (0: none)
    std::vector<uint8_t> owns_;      // per face: bit k, corner k samples its vertex; bit 3 + k, edge k (corner k to k + 1) its points
    std::vector<uint64_t> first_;    // per face: its first face sample's number (first_[faces]: their count)
    std::vector<uint32_t> order_;    // the faces in Morton order of their centroids
    std::vector<size_t> cuts_;       // batch k: order_[cuts_[k], cuts_[k + 1])
};

} // namespace tom::detail
