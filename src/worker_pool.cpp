// A fixed set of worker threads: see worker_pool.hpp.
#include "worker_pool.hpp"

#include <algorithm>
#include <stdexcept>

#include <unistd.h>

namespace bhgrasp {

WorkerPool::WorkerPool(int threads) : process_(getpid()) {
  if (threads < 1) throw std::invalid_argument("a worker pool needs at least one thread");
  errors_.resize(static_cast<std::size_t>(threads));
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  try {
    for (int block = 1; block < threads; ++block) workers_.emplace_back([this, block] { serve(block); });
  } catch (...) {  // a thread could not be made: end those that were
    stop();
    throw;
  }
}

WorkerPool::~WorkerPool() { stop(); }

bool WorkerPool::owned_here() const { return getpid() == process_; }

void WorkerPool::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& worker : workers_) worker.join();
  workers_.clear();
}

void WorkerPool::run_block(int block, int blocks, int n, const std::function<void(int)>& body) {
  const long first = static_cast<long>(block) * n / blocks, last = static_cast<long>(block + 1) * n / blocks;
  for (long i = first; i < last; ++i) body(static_cast<int>(i));
}

void WorkerPool::run(int n, const std::function<void(int)>& body) {
  const int blocks = std::max(1, std::min(threads(), n));
  if (blocks == 1) {
    for (int i = 0; i < n; ++i) body(i);
    return;
  }
  std::lock_guard<std::mutex> serial(serial_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    body_ = &body;
    n_ = n;
    blocks_ = blocks;
    running_ = blocks - 1;
    std::fill(errors_.begin(), errors_.end(), nullptr);
    ++loop_;
  }
  wake_.notify_all();
  try {
    run_block(0, blocks, n, body);
  } catch (...) {
    errors_[0] = std::current_exception();
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return running_ == 0; });
    body_ = nullptr;
  }
  for (auto& error : errors_)
    if (error) std::rethrow_exception(error);
}

void WorkerPool::serve(int block) {
  unsigned long seen = 0;
  for (;;) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [&] { return stop_ || loop_ != seen; });
    if (stop_) return;
    seen = loop_;
    if (block >= blocks_) continue;  // a loop of fewer blocks than threads
    const int blocks = blocks_, n = n_;
    const std::function<void(int)>& body = *body_;
    lock.unlock();
    std::exception_ptr error;
    try {
      run_block(block, blocks, n, body);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    errors_[static_cast<std::size_t>(block)] = error;
    if (--running_ == 0) done_.notify_one();
  }
}

}  // namespace bhgrasp
