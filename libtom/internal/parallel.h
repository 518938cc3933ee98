#pragma once
// How libtom runs a loop on several threads: blocks of a range taken in turn by up to `threads`
// threads, the caller's among them. A Team keeps its threads for a run of short loops (the
// builder's passes); parallel_blocks makes one for a single loop (error-curve points, metric
// samples).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "platform.h"

namespace tom::detail {

/// An allocator that leaves trivial elements uninitialized where std::allocator value-initializes
/// them (a vector's resize(n) writes nothing): for arrays a team fills, each thread first
/// touching the pages of its part (zero_on_team).
template <class T>
struct UninitializedAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitializedAllocator<U>;
    };
    UninitializedAllocator() noexcept = default;
    template <class U>
    UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};
template <class T>
using TeamVector = std::vector<T, UninitializedAllocator<T>>;

/// `threads`, or one per core for 0.
inline unsigned thread_count(unsigned threads) noexcept { return threads ? threads : std::max(1u, std::thread::hardware_concurrency()); }

/// Helper threads kept for a run of many short parallel loops (the builder's passes: several
/// loops per pass, a hundred passes), so a loop costs a hand-over instead of creating and joining
/// threads (each costs as much as a sleeping thread's wake-up). Runs work(worker,
/// begin, end) as parallel_blocks describes; one loop at a time, from the team's owner.
/// Between loops a helper spins for up to kSpin before it sleeps (yielding its core between looks
/// after the first kSpinAlone), so loops separated by short sequential work start at once. A
/// helper joins a loop only while it is open: once the owner has taken every block it closes the
/// loop and waits only for the helpers that joined, so a helper the system is not running (on a
/// machine where other work holds a core) does not hold it up. A team made for one loop (`spin` false) never spins: its threads wait
/// asleep, leaving the cores to other work (the report runs its levels and its error curve at
/// once, more threads than cores, where spinning would take time from the work).
class Team {
public:
    explicit Team(unsigned threads, bool spin = true) : spinning_(spin) {
        const unsigned want = std::max(1u, thread_count(threads));
        try {
            for (unsigned k = 1; k < want; ++k) pool_.emplace_back([this, k] { serve(k); });
        } catch (const std::system_error&) {  // the system refused a thread: work with fewer
        }
        size_ = unsigned(1 + pool_.size());
    }
    ~Team() {
        {
            const std::lock_guard<std::mutex> hold(lock_);
            quit_ = true;
        }
        wake_.notify_all();
        for (std::thread& t : pool_) t.join();
    }
    Team(const Team&) = delete;
    Team& operator=(const Team&) = delete;

    unsigned size() const noexcept { return size_; }

    template <class Work>
    void blocks(size_t count, size_t block, Work&& work) {
        const size_t blocks = (count + block - 1) / block;
        if (blocks <= 1 || size_ == 1) {  // not worth a hand-over
            for (size_t b = 0; b < blocks; ++b) work(0u, b * block, std::min(count, b * block + block));
            return;
        }
        using W = std::remove_reference_t<Work>;
        auto call = [](void* w, unsigned worker, size_t begin, size_t end) { (*static_cast<W*>(w))(worker, begin, end); };
        job_ = {call, const_cast<void*>(static_cast<const void*>(&work)), count, block, blocks};
        next_.store(0, std::memory_order_relaxed);
        failure_ = nullptr;
        left_.store(0, std::memory_order_relaxed);
        entry_.store(0, std::memory_order_release);  // open: helpers may join
        {
            const std::lock_guard<std::mutex> hold(lock_);
            generation_.fetch_add(1, std::memory_order_release);
        }
        wake_.notify_all();
        take(0);
        // every block is taken: close the job, and wait for the helpers that joined it (a helper
        // that is not running, on a busy machine, is not waited for)
        const uint32_t joined = entry_.fetch_or(kClosed, std::memory_order_acq_rel) & ~kClosed;
        auto finished = [this, joined] { return left_.load(std::memory_order_acquire) == joined; };
        if (!(spinning_ && spin(finished))) {
            std::unique_lock<std::mutex> hold(lock_);
            done_.wait(hold, finished);
        }
        if (failure_) std::rethrow_exception(failure_);
    }

private:
    struct Job {
        void (*call)(void*, unsigned, size_t, size_t) = nullptr;
        void* work = nullptr;
        size_t count = 0, block = 1, blocks = 0;
    };
    static constexpr std::chrono::microseconds kSpin{2000}, kSpinAlone{20};
    static constexpr uint32_t kClosed = 1u << 31;  // entry_: the job takes no more helpers

    // true once ready() holds, false when kSpin passed first
    template <class Ready>
    static bool spin(Ready&& ready) {
        const auto start = std::chrono::steady_clock::now();
        for (;;) {
            for (int i = 0; i < 64; ++i) {
                if (ready()) return true;
                cpu_relax();
            }
            const auto waited = std::chrono::steady_clock::now() - start;
            if (waited > kSpin) return false;
            // past the first moments, give the core to whoever else wants it between looks (the
            // thread this one waits for, when a busy machine put both on one core)
            if (waited > kSpinAlone) std::this_thread::yield();
        }
    }
    void take(unsigned worker) {
        try {
            for (size_t b; (b = next_++) < job_.blocks;) job_.call(job_.work, worker, b * job_.block, std::min(job_.count, b * job_.block + job_.block));
        } catch (...) {
            const std::lock_guard<std::mutex> hold(lock_);
            if (!failure_) failure_ = std::current_exception();
            next_ = job_.blocks;
        }
    }
    void serve(unsigned worker) {
        uint64_t seen = 0;
        for (;;) {
            if (!(spinning_ && spin([&] { return generation_.load(std::memory_order_acquire) != seen || quit_.load(std::memory_order_relaxed); }))) {
                std::unique_lock<std::mutex> hold(lock_);
                wake_.wait(hold, [&] { return quit_.load(std::memory_order_relaxed) || generation_.load(std::memory_order_acquire) != seen; });
            }
            if (quit_.load(std::memory_order_relaxed)) return;
            seen = generation_.load(std::memory_order_acquire);
            // join the job unless the owner closed it (it took every block itself); a helper late
            // for one job may join the next: it is the current one, set up before it opened
            uint32_t entry = entry_.load(std::memory_order_acquire);
            bool joined = false;
            while (!(entry & kClosed))
                if (entry_.compare_exchange_weak(entry, entry + 1, std::memory_order_acq_rel, std::memory_order_acquire)) {
                    joined = true;
                    break;
                }
            if (!joined) continue;
            take(worker);
            left_.fetch_add(1, std::memory_order_acq_rel);
            {
                const std::lock_guard<std::mutex> hold(lock_);  // the owner is spinning, or checked and is about to wait
            }
            done_.notify_one();
        }
    }

    bool spinning_;
    unsigned size_ = 1;
    std::vector<std::thread> pool_;
    std::mutex lock_;
    std::condition_variable wake_, done_;
    Job job_;
    std::atomic<size_t> next_{0};
    std::exception_ptr failure_;
    std::atomic<uint32_t> entry_{kClosed};  // helpers that joined the current job, and kClosed once it takes no more
    std::atomic<uint32_t> left_{0};         // helpers that joined it and are done
    std::atomic<uint64_t> generation_{0};
    std::atomic<bool> quit_{false};
};

/// v as `count` value-initialized elements (zeros), written by the team (large arrays: the
/// pages are faulted in and cleared on every thread instead of one).
template <class T>
void zero_on_team(Team& team, TeamVector<T>& v, size_t count) {
    static_assert(std::is_trivially_copyable<T>::value, "zeroed as plain values");
    v.clear();
    v.resize(count);
    T* p = v.data();
    team.blocks(count, std::max<size_t>(1, (size_t(1) << 20) / sizeof(T)), [p](unsigned, size_t begin, size_t end) { std::fill(p + begin, p + end, T{}); });
}

/// Runs work(worker, begin, end) over [0, count) in blocks of `block`, on up to thread_count(threads)
/// threads (never more than there are blocks); `worker` is 0 for the caller's thread and 1, 2, ...
/// for the others, so each can keep state of its own. The first exception a block throws
/// (std::bad_alloc) stops the others after their current block and is rethrown to the caller
/// once every thread has stopped. A Team made for this one loop.
template <class Work>
void parallel_blocks(size_t count, size_t block, unsigned threads, Work&& work) {
    const size_t blocks = (count + block - 1) / block;
    Team team(unsigned(std::min<size_t>(thread_count(threads), std::max<size_t>(1, blocks))), false);
    team.blocks(count, block, work);
}

/// Per-vertex sums over triangles without races or reordering: the vertices are cut into one
/// range per team thread, and each thread visits, in ascending order, the triangles with a corner
/// in its range, calling visit(t, lo, hi); visit adds t's terms to its corners in [lo, hi) only.
/// Every vertex then receives its terms in ascending triangle order, as a sequential scatter
/// would add them: the sums are bit-identical whatever the thread count. A triangle spanning two
/// ranges is visited by both threads.
template <class Visit>
void scatter_by_vertex_range(Team& team, uint32_t vertex_count, const uint32_t* indices, uint32_t triangle_count, Visit&& visit) {
    const unsigned parts = team.size();
    team.blocks(parts, 1, [&](unsigned, size_t part, size_t) {
        const uint32_t lo = uint32_t(uint64_t(vertex_count) * part / parts), hi = uint32_t(uint64_t(vertex_count) * (part + 1) / parts);
        for (uint32_t t = 0; t < triangle_count; ++t) {
            const uint32_t* c = indices + 3 * size_t(t);
            if ((c[0] >= lo && c[0] < hi) || (c[1] >= lo && c[1] < hi) || (c[2] >= lo && c[2] < hi)) visit(t, lo, hi);
        }
    });
}

} // namespace tom::detail
