#pragma once
// The one way libtom runs a loop on several threads (builder passes, error-curve points, metric
// samples): blocks of a range taken in turn by up to `threads` threads, the caller's among them.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tom::detail {

/// `threads`, or one per core for 0.
inline unsigned thread_count(unsigned threads) noexcept { return threads ? threads : std::max(1u, std::thread::hardware_concurrency()); }

/// Runs work(worker, begin, end) over [0, count) in blocks of `block`, on up to thread_count(threads)
/// threads (never more than there are blocks); `worker` is 0 for the caller's thread and 1, 2, ...
/// for the others, so each can keep state of its own. The first exception a block throws
/// (std::bad_alloc) stops the others after their current block and is rethrown to the caller
/// once every thread has stopped.
template <class Work>
void parallel_blocks(size_t count, size_t block, unsigned threads, Work&& work) {
    const size_t blocks = (count + block - 1) / block;
    const unsigned used = unsigned(std::min<size_t>(thread_count(threads), std::max<size_t>(1, blocks)));
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_lock;
    auto run = [&](unsigned worker) {
        try {
            for (size_t b; (b = next++) < blocks;) work(worker, b * block, std::min(count, b * block + block));
        } catch (...) {
            const std::lock_guard<std::mutex> hold(failure_lock);
            if (!failure) failure = std::current_exception();
            next = blocks;
        }
    };
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < used; ++k) pool.emplace_back(run, k);
    run(0);
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
}

} // namespace tom::detail
