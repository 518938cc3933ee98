#pragma once
// The one least-significant-digit radix sort of libtom: the builder's vertices by Morton code
// and its candidates by cost, the Metro-style samples' edges (and the samples themselves, by
// Morton code, where they are few: metrics/samples.cpp sorts many in fewer passes).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "parallel.h"

namespace tom::detail {

constexpr size_t kParallelSortItems = size_t(1) << 16, kSmallSortItems = size_t(1) << 14;

/// One stable counting pass: each item into `other` by its digit (key(item) >> shift) & (2^bits -
/// 1). With a team and at least 65,536 items, each team thread counts and then places one
/// contiguous part, the parts' places in each bucket in part order: the same result as on one
/// thread. `counts` is scratch (parts x 2^bits); after a pass, counts[(parts - 1) 2^bits + b] is
/// where bucket b ends. Returns false, having moved nothing, when every item has the same digit.
template <class T, class Key>
bool radix_pass(const std::vector<T>& items, std::vector<T>& other, int shift, int bits, Key key, Team* team, std::vector<size_t>& counts) {
    const size_t n = items.size(), buckets = size_t(1) << bits;
    other.resize(n);
    const size_t parts = team && n >= kParallelSortItems ? team->size() : 1;
    counts.resize(parts * buckets);  // part-major
    auto each_part = [&](auto&& f) {  // f(part, begin, end) for every part, on the team if any
        if (parts == 1) return f(size_t(0), size_t(0), n);
        team->blocks(parts, 1, [&](unsigned, size_t part, size_t) { f(part, n * part / parts, n * (part + 1) / parts); });
    };
    each_part([&](size_t part, size_t begin, size_t end) {
        size_t* count = &counts[part * buckets];
        std::fill(count, count + buckets, size_t(0));
        for (size_t i = begin; i < end; ++i) ++count[(uint64_t(key(items[i])) >> shift) & (buckets - 1)];
    });
    // each part's first place in each bucket: the buckets in order, within one the parts in order
    size_t sum = 0;
    bool one_digit = false;
    for (size_t b = 0; b < buckets; ++b) {
        size_t in_bucket = 0;
        for (size_t part = 0; part < parts; ++part) in_bucket += counts[part * buckets + b];
        if (in_bucket == n) one_digit = true;
        for (size_t part = 0; part < parts; ++part) sum += std::exchange(counts[part * buckets + b], sum);
    }
    if (one_digit) return false;
    each_part([&](size_t part, size_t begin, size_t end) {
        size_t* place = &counts[part * buckets];
        for (size_t i = begin; i < end; ++i) other[place[(uint64_t(key(items[i])) >> shift) & (buckets - 1)]++] = items[i];
    });
    return true;
}

/// Sorts `items` by key(item) (keys below 2^key_bits), equal keys in their input order: 12 bits
/// a pass (8 below kSmallSortItems items), passes where every key has the same digit skipped;
/// `other` is scratch. With a team, as radix_pass(): the same result as on one thread.
template <class T, class Key>
void radix_sort(std::vector<T>& items, std::vector<T>& other, int key_bits, Key key, Team* team = nullptr) {
    // digits of 12 bits; of 8 for a few items, whose passes would otherwise mostly walk buckets
    const int bits = items.size() < kSmallSortItems ? 8 : 12;
    std::vector<size_t> counts;
    for (int shift = 0; shift < key_bits; shift += bits)
        if (radix_pass(items, other, shift, bits, key, team, counts)) items.swap(other);
}

/// The same on up to thread_count(threads) threads, a team made for the sort when it is large
/// enough to share.
template <class T, class Key>
void radix_sort(std::vector<T>& items, std::vector<T>& other, int key_bits, Key key, unsigned threads) {
    if (items.size() >= kParallelSortItems && thread_count(threads) > 1) {
        Team team(thread_count(threads), false);
        radix_sort(items, other, key_bits, key, &team);
    } else {
        radix_sort(items, other, key_bits, key);
    }
}

} // namespace tom::detail
