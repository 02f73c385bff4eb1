// A fixed set of worker threads that run the blocks of one loop at a time (the batched stepper, batch.cpp).
//
// The threads are made once and sleep between loops, so a loop of a few hundred microseconds (one step of a batch)
// does not pay for creating and joining threads.  The caller's thread runs the first block itself; run() returns
// when every block is done and rethrows the first exception a block raised (in block order).  One loop runs at a time:
// a second caller of run() waits for the first.  A fork()ed child has none of the workers: owned_here() tells, and
// such a pool must be let go (leaked), not used or destroyed, since its destructor would wait for threads that are
// not there.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <sys/types.h>

namespace bhgrasp {

class WorkerPool {
 public:
  explicit WorkerPool(int threads);  // threads >= 1: the caller plus threads - 1 workers
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  bool owned_here() const;  // made in this process (not a fork's copy)

  // body(i) for every i in [0, n), in min(threads(), n) contiguous blocks of i, block b on one thread in order.
  void run(int n, const std::function<void(int)>& body);

 private:
  void serve(int block);  // a worker's life: wait for a loop, run its block, report; until the pool ends
  void stop();            // end and join the workers
  static void run_block(int block, int blocks, int n, const std::function<void(int)>& body);

  std::vector<std::thread> workers_;
  std::mutex serial_;  // one loop at a time
  std::mutex mutex_;   // guards what follows
  std::condition_variable wake_, done_;
  const std::function<void(int)>* body_ = nullptr;
  int n_ = 0, blocks_ = 0, running_ = 0;
  unsigned long loop_ = 0;  // counts loops, so that a worker wakes once per loop
  bool stop_ = false;
  std::vector<std::exception_ptr> errors_;  // per block
  pid_t process_;                           // the process whose threads these are
};

}  // namespace bhgrasp
