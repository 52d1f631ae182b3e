#include "app/mpi_session.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <new>
#include <stdexcept>

#include "analysis/util/error.h"
#include "app/flags.h"

#ifdef PANDORA_HAVE_MPI
#include <mpi.h>
#endif

namespace pandora::app {
namespace {
bool g_quiet_errors = false;
}  // namespace

bool MpiQuietErrors() { return g_quiet_errors; }

#ifdef PANDORA_HAVE_MPI

bool MpiAvailable() { return true; }

MpiSession::MpiSession(bool use) {
  if (!use) return;
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  active_ = true;
  g_quiet_errors = rank_ != 0;
}

MpiSession::~MpiSession() {
  if (!active_) return;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

bool MpiSession::AllOk(bool ok) const {
  if (!active_) return ok;
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

void MpiSession::ThrowIfAnyFailed(std::exception_ptr failure) const {
  if (!active_) {
    if (failure) std::rethrow_exception(failure);
    return;
  }
  int mine = failure ? rank_ : size_, first = size_;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == size_) return;
  // The first failing rank's error, as its four parts, to every process.
  std::string text;
  if (rank_ == first) {
    try {
      std::rethrow_exception(failure);
    } catch (const InputError& original) {
      const InputError e = ForCommandLine(original);  // the flags, as main() prints them
      text = e.file() + '\0' + e.json_path() + '\0' + e.reason() + '\0' + e.hint();
    } catch (const std::bad_alloc&) {
      text = std::string("") + '\0' + "" + '\0' + "out of memory" + '\0' +
             "close other programs, or lower the work";
    } catch (const std::exception& e) {
      text = std::string("") + '\0' + "" + '\0' + e.what() + '\0' + "";
    }
  }
  std::int64_t n = static_cast<std::int64_t>(text.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, first, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(n));
  MPI_Bcast(text.data(), static_cast<int>(n), MPI_BYTE, first, MPI_COMM_WORLD);
  std::string part[4];
  std::size_t at = 0;
  for (int k = 0; k < 4; ++k) {
    const std::size_t end = k < 3 ? text.find('\0', at) : text.size();
    part[k] = text.substr(at, end == std::string::npos ? std::string::npos : end - at);
    at = end == std::string::npos ? text.size() : end + 1;
  }
  const InputError error(
      part[0], part[1],
      part[2] + (first == 0 ? "" : " (on MPI rank " + std::to_string(first) + ")"), part[3]);
  // Rank 0 prints the one line before any process exits: mpirun kills the others as soon as one
  // process ends with an error, and rank 0 could be killed before it printed.
  if (rank_ == 0) {
    std::fprintf(stderr, "pandora: error: %s\n", error.what());
    std::fflush(stderr);
    g_quiet_errors = true;
  }
  MPI_Barrier(MPI_COMM_WORLD);
  throw error;
}

std::vector<std::string> MpiSession::GatherToRoot(const std::string& bytes) const {
  std::vector<std::string> out;
  if (!active_) {
    out.push_back(bytes);
    return out;
  }
  constexpr std::size_t kPiece = std::size_t(1) << 30;
  if (rank_ != 0) {
    const std::int64_t n = static_cast<std::int64_t>(bytes.size());
    MPI_Send(&n, 1, MPI_INT64_T, 0, 0, MPI_COMM_WORLD);
    for (std::size_t at = 0; at < bytes.size(); at += kPiece) {
      const int len = static_cast<int>(std::min(kPiece, bytes.size() - at));
      MPI_Send(bytes.data() + at, len, MPI_BYTE, 0, 1, MPI_COMM_WORLD);
    }
    return out;
  }
  out.resize(size_);
  out[0] = bytes;
  for (int r = 1; r < size_; ++r) {
    std::int64_t n = 0;
    MPI_Recv(&n, 1, MPI_INT64_T, r, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    out[r].resize(static_cast<std::size_t>(n));
    for (std::size_t at = 0; at < out[r].size(); at += kPiece) {
      const int len = static_cast<int>(std::min(kPiece, out[r].size() - at));
      MPI_Recv(out[r].data() + at, len, MPI_BYTE, r, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
  }
  return out;
}

std::string MpiSession::Broadcast(const std::string& bytes) const {
  if (!active_) return bytes;
  std::int64_t n = rank_ == 0 ? static_cast<std::int64_t>(bytes.size()) : 0;
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  std::string out = rank_ == 0 ? bytes : std::string(static_cast<std::size_t>(n), '\0');
  constexpr std::size_t kPiece = std::size_t(1) << 30;
  for (std::size_t at = 0; at < out.size(); at += kPiece) {
    const int len = static_cast<int>(std::min(kPiece, out.size() - at));
    MPI_Bcast(out.data() + at, len, MPI_BYTE, 0, MPI_COMM_WORLD);
  }
  return out;
}

#else

bool MpiAvailable() { return false; }

MpiSession::MpiSession(bool use) {
  if (use)
    throw InputError(
        "--mpi", "", "this pandora was built without MPI",
        "install libopenmpi-dev and openmpi-bin (scripts/setup.sh does) and build again");
}

MpiSession::~MpiSession() = default;

bool MpiSession::AllOk(bool ok) const { return ok; }

void MpiSession::ThrowIfAnyFailed(std::exception_ptr failure) const {
  if (failure) std::rethrow_exception(failure);
}

std::vector<std::string> MpiSession::GatherToRoot(const std::string& bytes) const {
  return {bytes};
}

std::string MpiSession::Broadcast(const std::string& bytes) const { return bytes; }

#endif

}  // namespace pandora::app
