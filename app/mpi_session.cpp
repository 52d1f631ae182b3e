#include "app/mpi_session.h"

#include <algorithm>
#include <cstdint>

#include "analysis/error.h"

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
    throw InputError("--mpi", "", "this pandora was built without MPI",
                     "install libopenmpi-dev and openmpi-bin (scripts/setup.sh does) and build again");
}

MpiSession::~MpiSession() = default;

bool MpiSession::AllOk(bool ok) const { return ok; }

std::vector<std::string> MpiSession::GatherToRoot(const std::string& bytes) const { return {bytes}; }

std::string MpiSession::Broadcast(const std::string& bytes) const { return bytes; }

#endif

}  // namespace pandora::app
