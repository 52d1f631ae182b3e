#pragma once
/// \file jobs.h
/// Background jobs with progress, cancellation and latest-wins semantics: one worker per kind
/// ("fields", "render", "suggest"); submitting a job of a kind cancels the running one of that kind
/// and replaces any job still waiting, so a viewer dragging a camera only ever computes the newest
/// state. Errors (InputError and others) end the job as failed with their message; they never
/// escape the worker.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace pandora::session {

/// What a running job sees: where to report progress, and whether it should stop.
class JobContext {
 public:
  /// Fraction done in [0, 1]; thread-safe, cheap.
  void Progress(double fraction) { progress_.store(fraction, std::memory_order_relaxed); }
  bool cancelled() const { return cancel_.load(std::memory_order_relaxed); }
  /// The flag itself, for libraries that poll one (FieldOptions::cancel).
  const std::atomic<bool>& cancel_flag() const { return cancel_; }

 private:
  friend class Jobs;
  std::atomic<bool> cancel_{false};
  std::atomic<double> progress_{0.0};
};

enum class JobState { kIdle, kQueued, kRunning, kDone, kCancelled, kFailed };
const char* JobStateName(JobState state);

struct JobStatus {
  JobState state = JobState::kIdle;
  std::int64_t id = 0;  ///< Of the job the state describes (0: none yet).
  double progress = 0;  ///< Of the running job.
  std::string error;    ///< With kFailed: the message.
  /// With kFailed: the exception itself, so a caller that waits can rethrow it (a command turns an
  /// InputError into its one-line message and exit code 2).
  std::exception_ptr exception;
};

class Jobs {
 public:
  Jobs() = default;
  ~Jobs();  ///< Cancels every job and waits for the workers.
  Jobs(const Jobs&) = delete;
  Jobs& operator=(const Jobs&) = delete;

  /// Queues `work` as the next job of `kind` (latest wins); returns its id (increasing).
  std::int64_t Submit(const std::string& kind, std::function<void(JobContext&)> work);
  /// Cancels the running and the waiting job of `kind`.
  void Cancel(const std::string& kind);
  /// Blocks until `kind` has nothing running or waiting; returns the last job's status.
  JobStatus Wait(const std::string& kind);
  JobStatus Status(const std::string& kind) const;

 private:
  struct Worker {
    std::thread thread;
    std::function<void(JobContext&)> pending;
    std::int64_t pending_id = 0;
    std::shared_ptr<JobContext> running;
    JobStatus status;
    bool busy = false;  // a thread is running the loop
  };
  void Loop(const std::string& kind);
  mutable std::mutex mutex_;
  std::condition_variable idle_;
  std::map<std::string, Worker> workers_;
  std::int64_t next_id_ = 0;
  bool stopping_ = false;
};

}  // namespace pandora::session
