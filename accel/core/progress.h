// SPDX-License-Identifier: MIT
// Progress of a long library computation (a build, EPO), counted from any thread and handed to
// the caller's function now and then: the CLI prints a percentage and the time left with it.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>

namespace bvhlab::accel {

/// What a long computation calls with its progress: `done` of `total` units of work.
using ProgressFn = std::function<void(uint64_t done, uint64_t total)>;

/// Counts units of work done by any number of threads. add() is an atomic addition; the
/// function is called with the count at most every `period_s` seconds, by whichever thread
/// adds then, never by two threads at once (a thread that finds it busy goes on without
/// calling), and with done < total (finish() or the owner's last report says all is done).
/// Work that may exceed its estimate (references that spatial splits duplicate) is reported
/// as at most total - 1 until then.
class ProgressCounter {
public:
    ProgressCounter(ProgressFn fn, uint64_t total, double period_s = 0.25)
        : fn_(std::move(fn)), total_(std::max<uint64_t>(total, 1)), period_(period_s) {
        last_ = std::chrono::steady_clock::now();
    }

    void add(uint64_t n) {
        const uint64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
        if (!fn_) return;
        const auto now = std::chrono::steady_clock::now();
        std::unique_lock<std::mutex> lock(mu_, std::try_to_lock);
        if (!lock.owns_lock() || std::chrono::duration<double>(now - last_).count() < period_) return;
        last_ = now;
        fn_(std::min(done, total_ - 1), total_);
    }
    /// Calls the function with done == total, once.
    void finish() {
        std::lock_guard<std::mutex> lock(mu_);
        if (fn_ && !finished_) fn_(total_, total_);
        finished_ = true;
    }
    uint64_t done() const { return done_.load(std::memory_order_relaxed); }
    uint64_t total() const { return total_; }

private:
    ProgressFn fn_;
    uint64_t total_;
    double period_;
    std::atomic<uint64_t> done_{0};
    std::mutex mu_;
    std::chrono::steady_clock::time_point last_;
    bool finished_ = false;
};

}  // namespace bvhlab::accel
