#include "app/session/jobs.h"

#include <exception>

namespace pandora::session {

const char* JobStateName(JobState state) {
  switch (state) {
    case JobState::kIdle:
      return "idle";
    case JobState::kQueued:
      return "queued";
    case JobState::kRunning:
      return "running";
    case JobState::kDone:
      return "done";
    case JobState::kCancelled:
      return "cancelled";
    case JobState::kFailed:
      return "failed";
  }
  return "?";
}

Jobs::~Jobs() {
  std::map<std::string, Worker>* workers = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    for (auto& [kind, w] : workers_) {
      w.pending = nullptr;
      if (w.running) w.running->cancel_ = true;
    }
    workers = &workers_;
  }
  for (auto& [kind, w] : *workers)
    if (w.thread.joinable()) w.thread.join();
}

std::int64_t Jobs::Submit(const std::string& kind, std::function<void(JobContext&)> work) {
  std::lock_guard<std::mutex> lock(mutex_);
  Worker& w = workers_[kind];
  const std::int64_t id = ++next_id_;
  if (w.running) w.running->cancel_ = true;  // latest wins
  w.pending = std::move(work);
  w.pending_id = id;
  w.status = JobStatus{JobState::kQueued, id, 0.0, {}, {}};
  if (!w.busy) {
    if (w.thread.joinable()) w.thread.join();  // the previous loop has ended
    w.busy = true;
    w.thread = std::thread([this, kind] { Loop(kind); });
  }
  return id;
}

void Jobs::Loop(const std::string& kind) {
  std::unique_lock<std::mutex> lock(mutex_);
  Worker& w = workers_[kind];
  while (w.pending && !stopping_) {
    std::function<void(JobContext&)> work = std::move(w.pending);
    w.pending = nullptr;
    const std::int64_t id = w.pending_id;
    auto context = std::make_shared<JobContext>();
    w.running = context;
    w.status = JobStatus{JobState::kRunning, id, 0.0, {}, {}};
    lock.unlock();
    JobStatus end{JobState::kDone, id, 1.0, {}, {}};
    try {
      work(*context);
      if (context->cancelled()) end.state = JobState::kCancelled;
    } catch (const std::exception& e) {
      end = JobStatus{context->cancelled() ? JobState::kCancelled : JobState::kFailed, id,
                      context->progress_.load(), e.what(), std::current_exception()};
    } catch (...) {
      end = JobStatus{JobState::kFailed, id, context->progress_.load(), "unknown error",
                      std::current_exception()};
    }
    lock.lock();
    w.running.reset();
    if (!w.pending) w.status = end;  // a newer job's kQueued status stays until it runs
  }
  w.busy = false;
  idle_.notify_all();
}

void Jobs::Cancel(const std::string& kind) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = workers_.find(kind);
  if (it == workers_.end()) return;
  Worker& w = it->second;
  if (w.pending) {
    w.pending = nullptr;
    w.status = JobStatus{JobState::kCancelled, w.pending_id, 0.0, {}, {}};
  }
  if (w.running) w.running->cancel_ = true;
}

JobStatus Jobs::Wait(const std::string& kind) {
  std::unique_lock<std::mutex> lock(mutex_);
  auto it = workers_.find(kind);
  if (it == workers_.end()) return {};
  idle_.wait(lock, [&] { return !it->second.busy; });
  return it->second.status;
}

JobStatus Jobs::Status(const std::string& kind) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = workers_.find(kind);
  if (it == workers_.end()) return {};
  JobStatus s = it->second.status;
  if (it->second.running) s.progress = it->second.running->progress_.load();
  return s;
}

}  // namespace pandora::session
