// libtom's internal thread team (libtom/internal/parallel.h): every block runs exactly once per loop,
// on the owner and the helpers, whether the helpers were spinning or asleep when the loop began;
// an exception thrown in a block reaches the owner, and the team keeps working afterwards.

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "parallel.h"

TEST_CASE("Team: each index once per loop, spinning or asleep", "[parallel]") {
    for (unsigned threads : {1u, 2u, 3u}) {
        tom::detail::Team team(threads);
        REQUIRE(team.size() >= 1);
        std::vector<int> hits(10007, 0);
        std::atomic<unsigned> workers_seen{0};
        std::atomic<bool> bad_worker{false};
        std::atomic<int> last_done{0};  // Catch2's assertions are not thread-safe: check after
        for (int loop = 0; loop < 300; ++loop) {
            if (loop % 100 == 99) std::this_thread::sleep_for(std::chrono::milliseconds(5));  // past the spin: helpers sleep
            team.blocks(hits.size(), 64, [&](unsigned worker, size_t begin, size_t end) {
                if (worker >= team.size()) bad_worker = true;
                workers_seen |= 1u << (worker & 31u);
                for (size_t i = begin; i < end; ++i) ++hits[i];
                // a slow last block: blocks() must not return while a helper is still in one
                if (end == hits.size()) std::this_thread::sleep_for(std::chrono::microseconds(200));
                if (end == hits.size()) last_done = loop + 1;
            });
            REQUIRE(last_done == loop + 1);
        }
        CHECK_FALSE(bad_worker);
        for (int h : hits) REQUIRE(h == 300);
        CHECK((workers_seen & 1u) == 1u);
        // a loop of one block runs on the owner alone
        unsigned owner_only = 0;
        team.blocks(10, 64, [&](unsigned worker, size_t, size_t) { owner_only += worker == 0; });
        CHECK(owner_only == 1);
    }
}

TEST_CASE("Team: an exception in a block reaches the owner, and the team goes on", "[parallel]") {
    tom::detail::Team team(2);
    for (int round = 0; round < 50; ++round) {
        const size_t bad_block = size_t(round % 20);
        CHECK_THROWS_AS(team.blocks(20 * 128, 128, [&](unsigned, size_t begin, size_t) {
            if (begin / 128 == bad_block) throw std::runtime_error("block failed");
        }), std::runtime_error);
        std::atomic<size_t> sum{0};
        team.blocks(1000, 10, [&](unsigned, size_t begin, size_t end) {
            for (size_t i = begin; i < end; ++i) sum += i;
        });
        REQUIRE(sum == 999u * 1000u / 2u);
    }
}

TEST_CASE("Team: short loops the owner finishes alone, helpers joining late or not at all", "[parallel]") {
    // a helper still waking from one loop may find it closed (the owner took every block) or join
    // the next one: every block of every loop must still run exactly once, and each loop must be
    // over when blocks() returns
    for (unsigned threads : {2u, 3u}) {
        for (const bool spin : {true, false}) {
            tom::detail::Team team(threads, spin);
            std::vector<int> hits(2 * 8, 0);
            std::atomic<int> running{0};
            std::atomic<bool> overlap{false}, bad_worker{false};
            int loops = 0;
            for (int loop = 0; loop < 5000; ++loop) {
                team.blocks(hits.size(), 8, [&](unsigned worker, size_t begin, size_t end) {
                    if (worker >= team.size()) bad_worker = true;
                    if (running.fetch_add(1) > 1) overlap = true;  // at most the two blocks of this loop
                    for (size_t i = begin; i < end; ++i) ++hits[i];
                    running.fetch_sub(1);
                });
                if (running.load() != 0) overlap = true;  // a block of this loop still in progress
                ++loops;
            }
            CHECK_FALSE(overlap);
            CHECK_FALSE(bad_worker);
            for (int h : hits) REQUIRE(h == loops);
        }
    }
}
