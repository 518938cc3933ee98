// The pass strategy: passes of independent substitutions taken cheapest first, the way
// meshoptimizer's simplifier takes its edge collapses (A. Kapoulkine, meshoptimizer). Each pass:
//   1. evaluate_dirty()     the vertices whose neighbourhood changed find their cheapest target
//   2. collect_candidates() those with one, sorted by cost as far as the loop will reach
//   3. substitute_pass()    walks them in order and applies each one that touches no vertex an
//                           earlier one of the pass touched and that the oracle allows
//   4. end_pass()           drops the removed vertices; a pass that applies nothing, after one
//                           full re-evaluation, ends the build
//
// The foresight is a layer over step 3 for a team of threads: before the sequential loop reaches
// a chunk of candidates, the team takes their oracle verdicts and their neighbours' costs of the
// target, and makes the previous chunk's quadric merges. A verdict is used only while nothing
// applied since has changed the fans the oracle read, and a foreseen cost only for a neighbour
// that has taken no merge since, so the loop applies the same substitutions in the same order
// with the layer on or off (BuildParams::foresight; the builder tests compare the files).

#include "passes.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "radix_sort.h"
#include "substitution.h"
#include "platform.h"

namespace tom::build_detail {

namespace {

// A candidate's cost as its bits: non-negative floats order like them.
inline uint32_t cost_bits(const Candidate& c) {
    uint32_t bits;
    std::memcpy(&bits, &c.cost, 4);
    return bits;
}

// Splits [0, count) in order: make(i) goes to the first list where which(i) is 1, to the second
// where it is 2, nowhere where 0; place(ones, twos) returns where the two lists start. The team
// counts and then places fixed blocks, so the order is the same whatever its size.
template <class T, class Which, class Make, class Place>
void split_in_order_to(detail::Team& team, size_t count, Which&& which, Make&& make, Place&& place_lists) {
    constexpr size_t kBlock = 8192;
    std::vector<size_t> place(2 * ((count + kBlock - 1) / kBlock));  // per block: its first places in first and second
    team.blocks(count, kBlock, [&](unsigned, size_t begin, size_t end) {
        size_t ones = 0, twos = 0;
        for (size_t i = begin; i < end; ++i) {
            const int w = which(i);
            ones += w == 1;
            twos += w == 2;
        }
        place[2 * (begin / kBlock)] = ones;
        place[2 * (begin / kBlock) + 1] = twos;
    });
    size_t ones = 0, twos = 0;
    for (size_t k = 0; k < place.size(); k += 2) {
        ones += std::exchange(place[k], ones);
        twos += std::exchange(place[k + 1], twos);
    }
    const std::pair<T*, T*> lists = place_lists(ones, twos);
    T* const first = lists.first;
    T* const second = lists.second;
    team.blocks(count, kBlock, [&](unsigned, size_t begin, size_t end) {
        size_t one = place[2 * (begin / kBlock)], two = place[2 * (begin / kBlock) + 1];
        for (size_t i = begin; i < end; ++i) {
            const int w = which(i);
            if (w == 1) first[one++] = make(i);
            else if (w == 2) second[two++] = make(i);
        }
    });
}

// split_in_order_to() into two vectors
template <class T, class Which, class Make>
void split_in_order(detail::Team& team, size_t count, Which&& which, Make&& make, std::vector<T>& first, std::vector<T>& second) {
    split_in_order_to<T>(team, count, which, make, [&](size_t ones, size_t twos) {
        first.resize(ones);
        second.resize(twos);
        return std::pair<T*, T*>(first.data(), second.data());
    });
}

// the top 11 bits below the sign: costs in coarse order
inline uint32_t cost_bucket(const Candidate& c) { return cost_bits(c) >> 21; }

// Candidates by cost, stable; the team shares a large sort (the same order).
void sort_candidates(std::vector<Candidate>& items, std::vector<Candidate>& tmp, detail::Team& team) {
    detail::radix_sort(items, tmp, 32, [](const Candidate& c) { return cost_bits(c); }, &team);  // (a lambda: inlined)
}

// The candidates of a pass in the order the loop takes them: the cheapest `keep` (at least: whole
// buckets) sorted, then the others in their original order. One list, sorted in two steps as
// the loop reaches them: sort_cheapest() puts the candidates make(i) for i in [0, count) where
// has(i) in `items`, the cheapest `first` (at least) sorted at the front and the others after
// them in order, and returns the last bucket of the cheapest `keep`; sort_next(), once the loop
// has passed the front, sorts the tail up to that bucket in place, the others staying after it
// in order. For the part the loop reaches this is the order of one full sort (buckets follow
// costs; equal costs share a bucket and keep their order); a pass rarely needs more than twice
// its quota, since independence rejects some candidates. Stable, deterministic. The list is never
// held whole twice: the scratch is the size of the part being sorted, which keeps a large mesh's
// first passes (10^7 triangles: the peak of the build) about 5 bytes a triangle lower.
template <class Has, class Make>
uint32_t sort_cheapest(size_t count, Has&& has, Make&& make, size_t first, size_t keep, std::vector<Candidate>& items, size_t& front,
                       detail::Team& team) {
    std::vector<uint32_t> hists(size_t(team.size()) * 2048, 0);  // per team thread (counts: their sum is the same)
    team.blocks(count, 8192, [&](unsigned worker, size_t begin, size_t end) {
        uint32_t* hist = &hists[size_t(worker) * 2048];
        for (size_t i = begin; i < end; ++i)
            if (has(i)) ++hist[cost_bucket(make(i))];
    });
    uint32_t limit_first = 2047, limit_keep = 2047;
    size_t sum = 0;
    for (uint32_t bucket = 0; bucket < 2048; ++bucket) {
        const size_t before = sum;
        for (unsigned worker = 0; worker < team.size(); ++worker) sum += hists[size_t(worker) * 2048 + bucket];
        if (before < first && sum >= first) limit_first = bucket;
        if (sum >= keep) {
            limit_keep = bucket;
            break;
        }
    }
    limit_first = std::min(limit_first, limit_keep);
    std::vector<Candidate> head, tmp;
    split_in_order_to<Candidate>(team, count, [&](size_t i) { return has(i) ? (cost_bucket(make(i)) <= limit_first ? 1 : 2) : 0; }, make,
                                 [&](size_t ones, size_t twos) {
                                     head.resize(ones);
                                     items.resize(ones + twos);
                                     return std::pair<Candidate*, Candidate*>(head.data(), items.data() + ones);
                                 });
    sort_candidates(head, tmp, team);
    std::copy(head.begin(), head.end(), items.begin());
    front = head.size();
    return limit_keep;
}
void sort_next(std::vector<Candidate>& items, size_t& front, uint32_t limit_keep, detail::Team& team) {
    size_t next_count = 0;
    for (size_t i = front; i < items.size(); ++i) next_count += cost_bucket(items[i]) <= limit_keep;
    std::vector<Candidate> next, tmp;
    next.reserve(next_count);
    size_t others_end = front;  // the others move up, in order, then to the end
    for (size_t i = front; i < items.size(); ++i) {
        if (cost_bucket(items[i]) <= limit_keep) next.push_back(items[i]);
        else items[others_end++] = items[i];
    }
    std::copy_backward(items.begin() + ptrdiff_t(front), items.begin() + ptrdiff_t(others_end), items.end());
    sort_candidates(next, tmp, team);
    std::copy(next.begin(), next.end(), items.begin() + ptrdiff_t(front));
    front = items.size();
}

// Runs f(i, scratch) for i in [0, count) on the team's threads (the caller's with `own`, each
// helper with its own scratch), in blocks of 16 to 512: eight or more a thread, so that a short
// loop (a late pass, a small mesh) is shared too. f must only write state that belongs to i.
template <class F>
void parallel_for(detail::Team& team, size_t count, Scratch& own, std::vector<Scratch>& helpers, F&& f) {
    const size_t block = std::min<size_t>(512, std::max<size_t>(16, count / (8 * size_t(team.size()))));
    team.blocks(count, block, [&](unsigned worker, size_t begin, size_t end) {
        Scratch& sc = worker == 0 ? own : helpers[worker - 1];
        for (size_t i = begin; i < end; ++i) f(i, sc);
    });
}

// What the team found out ahead of the sequential loop about one candidate v -> u of a pass.
enum Verdict : uint8_t { kLegal, kIllegal, kUnknown };
constexpr uint32_t kRingMax = 15;   // a ring or fan longer than this is not listed (rare: valence > 15)
constexpr uint32_t kChunkMax = 256; // candidates foreseen at once
constexpr uint8_t kRingUnknown = 255;
struct Foresight {
    uint8_t verdict;  // the oracle's: kLegal, kIllegal, or kUnknown (not asked)
    uint8_t ring;     // v's neighbours listed (when legal, quadric predicate), or kRingUnknown
    uint8_t fan;      // v's live triangles listed (the same), or kRingUnknown
    uint32_t w[kRingMax];
    float cost[kRingMax];  // quadric_cost(w[i], u) for an interior w[i] other than u
    uint32_t triangle[kRingMax];
};

// Per-vertex state of the strategy, kept across passes. Each vertex's best substitution is
// recomputed only when its neighbourhood changed (dirty). Costs alone pick it; the oracle runs
// when it is about to be applied, and a vertex whose cheapest target failed the oracle is
// evaluated with the oracle from then on (needs_oracle).
struct PassState {
    std::vector<uint32_t> live;  // vertices that may still move: not locked, not removed
    std::vector<Candidate> best;
    std::vector<uint8_t> has, dirty, needs_oracle;
    std::vector<uint32_t> pass_mark;  // the pass that last touched a vertex: one substitution each a pass
    uint32_t pass = 0;
    uint32_t alive_count = 0;
    bool full_rescan_done = false;
};

// The current pass's candidates in the order the loop takes them (see sort_cheapest).
struct PassCandidates {
    std::vector<Candidate> items;  // [0, front) sorted; the others after them, in vertex order
    size_t front = 0;              // grows to items.size() as the loop reaches its end
    uint32_t limit_keep = 0;
    size_t quota = 0;     // substitutions the pass may apply
    size_t executed = 0;  // vertices the pass removed so far
};

// The foresight layer's state (see the file's head).
struct Lookahead {
    bool on = false;  // for the current pass
    std::vector<Foresight> chunk_entries = std::vector<Foresight>(kChunkMax);
    size_t chunk_begin = 0, chunk_end = 0;  // the candidates foreseen: [chunk_begin, chunk_end)
    uint32_t chunk = 0;                     // the current chunk's number
    // per position class: the chunk during which a substitution last changed its fans; a
    // verdict of this chunk holds while its v's and u's classes are unmarked
    std::vector<uint32_t> touched;
    // a chunk's quadric merges (target, removed), made by the team with the next foresight: a
    // merge's target is dirty from then on, so nothing reads its quadric until the next pass
    // evaluates it, and each target takes one merge a pass (pass_mark): the same sums
    std::vector<std::pair<uint32_t, uint32_t>> merges;
};

class PassRunner {
public:
    PassRunner(Builder& b, float fraction, bool foresight, detail::Team& team, BuildStats& stats)
        : b_(b), topo_(b.topo), fraction_(fraction), foresight_(foresight), team_(team), stats_(stats), helpers_(team.size() - 1) {
        for (uint32_t v = 0; v < b.n; ++v)
            if (kCollapseRules[b.classes.kind[v]].moves) s_.live.push_back(v);
        s_.best.resize(b.n);
        s_.has.assign(b.n, 0);
        s_.dirty.assign(b.n, 1);
        s_.needs_oracle.assign(b.n, 0);
        s_.pass_mark.assign(b.n, 0);
        s_.alive_count = b.n;
        ahead_.touched.assign(b.n, 0);
        for (Scratch& h : helpers_) h.stamp.assign(b.n, 0);
        for (size_t k = 0; k < b.pieces.count(); ++k) piece_heads_.push_back(b.pieces.members[b.pieces.first[k]]);
    }

    std::function<void(double)> progress;  // after each pass: the share of the vertices removed

    void run() {
        for (s_.pass = 1;; ++s_.pass) {
            evaluate_dirty();
            collect_candidates();
            substitute_pass();
            if (c_.executed == 0) {
                if (!rescan_once()) break;
                continue;
            }
            end_pass();
            if (progress && b_.n) progress(double(b_.n - s_.alive_count) / double(b_.n));
        }
    }

private:
    // 1. The dirty vertices' best substitutions, on the team: each reads the shared state and
    // writes only its own best, has and dirty (the results do not depend on the thread count).
    void evaluate_dirty() {
        split_in_order(team_, s_.live.size(), [&](size_t i) { return int(s_.dirty[s_.live[i]]); }, [&](size_t i) { return s_.live[i]; }, evaluate_,
                       unused_);
        // two loops: compaction rewrites v's list, which another vertex's oracle may be walking
        // (each corner is in one list, so compactions do not meet); evaluation only reads lists
        parallel_for(team_, evaluate_.size(), b_.scratch, helpers_, [&](size_t i, Scratch&) { topo_.compact(evaluate_[i]); });
        parallel_for(team_, evaluate_.size(), b_.scratch, helpers_, [&](size_t i, Scratch& sc) {
            const uint32_t v = evaluate_[i];
            if (i + 8 < evaluate_.size()) b_.prefetch(evaluate_[i + 8]);
            if (i + 4 < evaluate_.size()) topo_.prefetch_fan(evaluate_[i + 4]);
            s_.has[v] = b_.best_target(v, s_.best[v], s_.needs_oracle[v] != 0, sc);
            s_.dirty[v] = 0;
        });
    }

    // 2. The vertices with a best substitution; the cheapest 4 x quota are enough to fill a pass
    // (the cheapest 2 x quota sorted now, the others when the loop gets there).
    // A piece's removal is a candidate too (v: its first member, u: kNone), in the same order.
    void collect_candidates() {
        c_.quota = std::max<size_t>(1, size_t(std::ceil(double(fraction_) * s_.alive_count)));
        const size_t live = s_.live.size();
        const Pieces& pieces = b_.pieces;
        c_.limit_keep = sort_cheapest(
            live + pieces.count(), [&](size_t i) { return i < live ? s_.has[s_.live[i]] != 0 : !pieces.gone[i - live]; },
            [&](size_t i) {
                if (i < live) return s_.best[s_.live[i]];
                const size_t k = i - live;
                return Candidate{pieces.cost[k], pieces.members[pieces.first[k]], kNone};
            },
            c_.quota * 2, c_.quota * 4, c_.items, c_.front, team_);
        c_.executed = 0;
    }

    // 3. The loop over the candidates; when none went through, once more over all of them.
    void substitute_pass() {
        for (int attempt = 0; attempt < 2 && c_.executed == 0 && !c_.items.empty(); ++attempt) {
            if (attempt == 1) take_all_candidates();
            begin_foresight();
            for (size_t ci = 0; c_.executed < c_.quota; ++ci) {
                if (!reach(ci)) break;
                if (ahead_.on && ci == ahead_.chunk_end) foresee_chunk(ci);
                prefetch_ahead(ci);
                try_candidate(ci);
            }
            end_foresight();
        }
    }

    void take_all_candidates() {
        std::vector<Candidate> tmp;
        sort_candidates(c_.items, tmp, team_);
        c_.front = c_.items.size();
        c_.quota = c_.items.size();
    }

    // false when the loop has passed every candidate; sorts more of them when it reaches the front's end
    bool reach(size_t ci) {
        if (ci < c_.front) return true;
        if (c_.front == c_.items.size()) return false;
        sort_next(c_.items, c_.front, c_.limit_keep, team_);
        return true;
    }

    void try_candidate(size_t ci) {
        const Candidate c = c_.items[ci];
        if (c.u == kNone) {
            prune(c.v);
            return;
        }
        if (s_.pass_mark[c.v] == s_.pass || s_.pass_mark[c.u] == s_.pass) return;  // not independent of this pass's earlier ones
        if (kCollapseRules[b_.classes.kind[c.v]].as_group)
            collapse_group(c);
        else
            collapse(c, ci);
    }

    // A group collapse: every copy of v's point moves, each onto a copy of u's point
    // (Builder::group_move); one step of the order, whatever its number of copies.
    void collapse_group(const Candidate& c) {
        GroupMove& move = group_;
        bool joins = false;
        bool ok = !b_.removed[c.v] && !b_.removed[c.u] && b_.group_move(c.v, c.u, true, move, b_.scratch, &joins) &&
                  (!joins || JoinRanking::ranked(c.cost, move.cost));
        for (uint32_t i = 0; ok && i < move.count; ++i) ok = s_.pass_mark[move.from[i]] != s_.pass && s_.pass_mark[move.to[i]] != s_.pass;
        if (!ok) {
            reject(c.v);
            return;
        }
        for (uint32_t i = 0; i < move.count; ++i) {
            ring_changed(move.from[i]);
            ring_changed(move.to[i]);
        }
        b_.group_steps.push_back({uint32_t(b_.removed_order.size()), move.count});
        for (uint32_t i = 0; i < move.count; ++i) {
            // merged now, not with the chunk: several copies may share a target
            b_.substitute(move.from[i], move.to[i]);
            b_.merge_quadrics(move.to[i], move.from[i]);
            topo_.splice(move.from[i], move.to[i]);
        }
        for (uint32_t i = 0; i < move.count; ++i) {
            s_.pass_mark[move.from[i]] = s_.pass_mark[move.to[i]] = s_.pass;
            s_.dirty[move.to[i]] = 1;
        }
        c_.executed += move.count;
    }

    // A piece removed whole: its live vertices but the first, each onto the first (which stays,
    // without triangles), one group of the order, so no resolution shows it half gone.
    void prune(uint32_t first_member) {
        Pieces& pieces = b_.pieces;
        const size_t k = size_t(std::lower_bound(piece_heads_.begin(), piece_heads_.end(), first_member) - piece_heads_.begin());
        if (pieces.gone[k]) return;
        uint32_t survivor = kNone;
        std::vector<uint32_t>& leaving = leaving_;
        leaving.clear();
        for (uint32_t i = pieces.first[k]; i < pieces.first[k + 1]; ++i) {
            const uint32_t v = pieces.members[i];
            if (b_.removed[v]) continue;
            if (s_.pass_mark[v] == s_.pass) return;  // a substitution of this pass changed it
            if (survivor == kNone) survivor = v;
            else leaving.push_back(v);
        }
        pieces.gone[k] = 1;
        if (leaving.empty()) return;
        for (const uint32_t v : leaving) touch(v);
        touch(survivor);
        b_.group_steps.push_back({uint32_t(b_.removed_order.size()), uint32_t(leaving.size())});
        for (const uint32_t v : leaving) {
            b_.substitute(v, survivor);
            topo_.splice(v, survivor);
            s_.pass_mark[v] = s_.pass;
        }
        s_.pass_mark[survivor] = s_.pass;
        c_.executed += leaving.size();
        ++stats_.pruned_pieces;
    }

    // A single substitution v -> u, when the oracle allows it.
    void collapse(const Candidate& c, size_t ci) {
        const uint8_t known = foreseen_verdict(c, ci);
        if (b_.removed[c.u] || !b_.border_move_allowed(c.v, c.u) || (known == kUnknown ? refused(c, b_.scratch) : known == kIllegal)) {
            reject(c.v);
            return;
        }
        const Foresight* f = known == kLegal ? &ahead_.chunk_entries[ci - ahead_.chunk_begin] : nullptr;
        if (b_.predicate == Predicate::quadric) {
            update_neighbour_costs(c, f);
            s_.dirty[c.u] = 1;  // u's quadric grows
        } else {
            ring_changed(c.v);
        }
        touch(c.u);  // a pair target gains v's fan
        substitute(c.v, c.u, f && f->fan != kRingUnknown ? f : nullptr);
        s_.pass_mark[c.v] = s_.pass_mark[c.u] = s_.pass;
        ++c_.executed;
    }

    // The oracle on a candidate as the pass applies it. A join of two sheets (Builder::illegal)
    // is taken only at the cost the oracle's ranking gave it, kJoinPenalty times its own
    // (JoinRanking; the factor is a power of two: the product is exact); costed without the
    // oracle (v's first evaluation, a neighbour's update) it is refused, and v looks again next
    // pass through the oracle. (Groups: collapse_group, the same on the move's summed cost.)
    bool refused(const Candidate& c, Scratch& sc) const {
        bool joins = false;
        return b_.illegal(c.v, c.u, sc, true, &joins) || (joins && !JoinRanking::ranked(c.cost, b_.cost(c.v, c.u)));
    }

    // v's candidate failed: look again next pass, through the oracle
    void reject(uint32_t v) {
        s_.dirty[v] = 1;
        s_.needs_oracle[v] = 1;
    }

    // After v -> u under the quadric predicate, the costs that change are those of v's neighbours,
    // whose target v becomes u. A neighbour w keeps its candidate unless that was v; it gains u as
    // a target, whose cost Q_w(p_u) is one evaluation (the foresight's, while w's quadric is as it
    // was). Borders and seams are evaluated again.
    void update_neighbour_costs(const Candidate& c, const Foresight* f) {
        auto neighbour = [&](uint32_t w, const float* foreseen) {
            if (b_.classes.kind[w] == kCopy) {  // its group's first copy decides for it
                s_.dirty[b_.classes.wedge[w]] = 1;
                return;
            }
            if (w == c.v || w == c.u || s_.dirty[w] || b_.classes.kind[w] == kLocked) return;
            if (!s_.has[w] || s_.best[w].u == c.v || b_.classes.kind[w] != kInterior) {
                s_.dirty[w] = 1;
                return;
            }
            float cw;
            if (foreseen) {
                cw = *foreseen;
            } else if (!b_.quadric_cost_within(w, c.u, s_.best[w].cost, s_.best[w].u, cw)) {
                return;
            }
            if (cw < s_.best[w].cost || (cw == s_.best[w].cost && c.u < s_.best[w].u)) s_.best[w] = {cw, w, c.u};
        };
        if (f && f->ring != kRingUnknown) {
            touch(c.v);
            for (uint32_t i = 0; i < f->ring; ++i) {
                touch(f->w[i]);
                neighbour(f->w[i], &f->cost[i]);
            }
        } else {
            b_.each_distinct_corner(c.v, b_.scratch, [&](uint32_t w) {
                touch(w);
                neighbour(w, nullptr);
            });
        }
    }

    // a substitution of x changes its ring: each of its vertices is looked at again next pass
    void ring_changed(uint32_t x) {
        b_.each_corner(x, [&](uint32_t w) {
            s_.dirty[w] = 1;
            s_.dirty[b_.classes.wedge[w]] = 1;  // a copy's group
            touch(w);
        });
    }

    // v -> u with the quadric merge and the corner lists' splice; over the foresight's list of
    // v's triangles when it has one
    void substitute(uint32_t v, uint32_t u, const Foresight* listed) {
        if (listed)
            b_.substitute_listed(v, u, listed->triangle, listed->fan);
        else
            b_.substitute(v, u);
        if (ahead_.on && b_.predicate == Predicate::quadric)
            ahead_.merges.push_back({u, v});
        else
            b_.merge_quadrics(u, v);
        topo_.splice(v, u);
    }

    // 4. The pass applied something: drop the removed vertices.
    void end_pass() {
        s_.full_rescan_done = false;
        ++stats_.passes;
        s_.alive_count -= uint32_t(c_.executed);
        split_in_order(team_, s_.live.size(), [&](size_t i) { return int(!b_.removed[s_.live[i]]); }, [&](size_t i) { return s_.live[i]; },
                       evaluate_, unused_);
        s_.live.swap(evaluate_);
    }

    // A pass applied nothing. Cached verdicts can be stale two rings away: one full
    // re-evaluation through the oracle before stopping. False when that was done already.
    bool rescan_once() {
        if (s_.full_rescan_done) return false;
        s_.full_rescan_done = true;
        std::fill(s_.dirty.begin(), s_.dirty.end(), 1);
        std::fill(s_.needs_oracle.begin(), s_.needs_oracle.end(), 1);
        return true;
    }

    // --- the foresight layer ---

    // On for this attempt when there is a team and the mesh is large enough: a chunk's
    // substitutions touch about 7 classes each, so on a small mesh most of the next verdicts
    // would be stale and their work lost (chunks are at most 1/64 of the mesh).
    void begin_foresight() {
        ahead_.on = foresight_ && team_.size() > 1 && s_.alive_count >= 64 * 32;
        ahead_.chunk_begin = ahead_.chunk_end = 0;
    }
    void end_foresight() {
        parallel_for(team_, ahead_.merges.size(), b_.scratch, helpers_, [&](size_t i, Scratch&) { b_.merge_quadrics(ahead_.merges, i); });
        ahead_.merges.clear();
        ahead_.on = false;
    }

    void touch(uint32_t w) {
        if (ahead_.on) ahead_.touched[b_.classes.wedge[w]] = ahead_.chunk;
    }

    // the verdict foreseen for candidate ci, while nothing applied since changed the fans the
    // oracle read (those of v's and u's position classes); kUnknown otherwise
    uint8_t foreseen_verdict(const Candidate& c, size_t ci) const {
        if (!ahead_.on) return kUnknown;
        const uint32_t* touched = ahead_.touched.data();
        const uint32_t* wedge = b_.classes.wedge.data();
        if (touched[wedge[c.v]] == ahead_.chunk || touched[wedge[c.u]] == ahead_.chunk) return kUnknown;
        return ahead_.chunk_entries[ci - ahead_.chunk_begin].verdict;
    }

    // The next chunk (about what the quota still needs), foreseen on the team from the state as it
    // is now, together with the previous chunk's merges.
    void foresee_chunk(size_t ci) {
        ++ahead_.chunk;
        ++stats_.foreseen_chunks;
        ahead_.chunk_begin = ci;
        const size_t length = std::min({size_t(kChunkMax), size_t(s_.alive_count / 64), std::max<size_t>(32, (c_.quota - c_.executed) * 5 / 4)});
        ahead_.chunk_end = std::min(c_.front, ci + length);
        const size_t pending = ahead_.merges.size(), begin = ahead_.chunk_begin, end = ahead_.chunk_end;
        parallel_for(team_, pending + (end - begin), b_.scratch, helpers_, [&](size_t i, Scratch& sc) {
            if (i < pending) {
                b_.merge_quadrics(ahead_.merges, i);
                return;
            }
            const size_t k = i - pending;
            // the reads of the candidates a little ahead started now (the chunk's vertices lie
            // anywhere in the mesh: its cost order, not its layout)
            if (begin + k + 8 < end) b_.prefetch(c_.items[begin + k + 8].v);
            if (begin + k + 4 < end) topo_.prefetch_fan(c_.items[begin + k + 4].v);
            foresee(c_.items[begin + k], ahead_.chunk_entries[k], sc);
        });
        ahead_.merges.clear();
    }

    // One candidate's verdict and, when legal under the quadric predicate, v's triangles and its
    // neighbours (their corners but v) with, for the interior ones, Q_w(p_u).
    void foresee(const Candidate& e, Foresight& f, Scratch& sc) const {
        f.verdict = kUnknown;
        f.ring = f.fan = kRingUnknown;
        if (e.u == kNone || s_.pass_mark[e.v] == s_.pass || s_.pass_mark[e.u] == s_.pass || kCollapseRules[b_.classes.kind[e.v]].as_group || b_.removed[e.u])
            return;
        f.verdict = refused(e, sc) ? kIllegal : kLegal;
        if (f.verdict == kIllegal || b_.predicate != Predicate::quadric) return;
        uint32_t ring = 0, fan = 0;
        b_.each_distinct_corner(
            e.v, sc,
            [&](uint32_t w) {
                if (w == e.v) return;
                if (ring < kRingMax) {
                    f.w[ring] = w;
                    f.cost[ring] = 0.0f;  // (used only for an interior w other than u that has a best and is clean)
                    // what the loop compares with w's best; where even the geometric term cannot
                    // beat that best, +inf (the loop's test fails as with the full cost: a best
                    // only falls within a pass, dirty stays dirty), and w's attribute quadric is not read
                    if (w != e.u && b_.classes.kind[w] == kInterior && s_.has[w] && !s_.dirty[w] &&
                        !b_.quadric_cost_within(w, e.u, s_.best[w].cost, s_.best[w].u, f.cost[ring]))
                        f.cost[ring] = std::numeric_limits<float>::infinity();
                }
                ++ring;
            },
            [&](uint32_t t) {
                if (fan < kRingMax) f.triangle[fan] = t;
                ++fan;
            });
        if (ring <= kRingMax) f.ring = uint8_t(ring);
        if (fan <= kRingMax) f.fan = uint8_t(fan);
    }

    // Starts the loads of the candidates two and four ahead (with the foresight's lists, the
    // next one's triangles and ring all at once instead of down its corner list).
    void prefetch_ahead(size_t ci) const {
        const Candidate* sorted = c_.items.data();  // the part in its final order: [0, front)
        if (ci + 4 < c_.front && sorted[ci + 4].u != kNone) {
            b_.prefetch(sorted[ci + 4].v);
            topo_.prefetch_splice(sorted[ci + 4].v, sorted[ci + 4].u);
        }
        if (ci + 2 >= c_.front) return;
        const Foresight* next = ahead_.on && ci + 2 < ahead_.chunk_end ? &ahead_.chunk_entries[ci + 2 - ahead_.chunk_begin] : nullptr;
        if (!next || next->fan == kRingUnknown) {
            topo_.prefetch_fan(sorted[ci + 2].v);  // (a piece's first member for a removal: harmless)
            return;
        }
        for (uint32_t i = 0; i < next->fan; ++i) {
            const size_t t = next->triangle[i];
            tom::detail::prefetch_write(&topo_.idx[3 * t]);
            tom::detail::prefetch_write(&topo_.dead[t]);
            tom::detail::prefetch_write(&topo_.death_step[t]);
        }
        if (next->ring == kRingUnknown) return;
        for (uint32_t i = 0; i < next->ring; ++i) {
            const uint32_t w = next->w[i];
            tom::detail::prefetch_write(&s_.best[w]);
            tom::detail::prefetch_write(&s_.dirty[w]);
            tom::detail::prefetch(&s_.has[w]);
            tom::detail::prefetch(&b_.classes.kind[w]);
            tom::detail::prefetch(&b_.classes.wedge[w]);
            tom::detail::prefetch_write(&ahead_.touched[w]);  // (its class's mark: w's own but for coincident copies)
        }
    }

    Builder& b_;
    Topology& topo_;
    const float fraction_;
    const bool foresight_;
    detail::Team& team_;
    BuildStats& stats_;
    PassState s_;
    PassCandidates c_;
    Lookahead ahead_;
    std::vector<uint32_t> evaluate_, unused_;  // (unused_: split_in_order's second list, always empty here)
    std::vector<Scratch> helpers_;
    GroupMove group_;  // collapse_group()'s (2 KB)
    std::vector<uint32_t> leaving_;      // prune()'s
    std::vector<uint32_t> piece_heads_;  // each prunable piece's first member, ascending (pieces are in that order)
};

} // namespace

void run_passes(Builder& b, float fraction, bool foresight, detail::Team& team, BuildStats& stats, const std::function<void(double)>& progress) {
    PassRunner runner(b, fraction, foresight, team, stats);
    runner.progress = progress;
    runner.run();
}

} // namespace tom::build_detail
