#pragma once
/// \file mpi_session.h
/// `pandora analyze --mpi` (docs/scale.md): the processes started by mpirun, each evaluating its
/// partition of the blocks, rank 0 gathering and writing. MPI's header stays in mpi_session.cpp;
/// without MPI at build time (CMake found no MPI) `--mpi` is refused with one line.

#include <exception>
#include <string>
#include <vector>

namespace pandora::app {

class MpiSession {
 public:
  /// `use` false: one process, rank 0 of 1, no MPI. `use` true: MPI_Init (once per process);
  /// throws InputError("--mpi", ...) when this build has no MPI.
  explicit MpiSession(bool use);
  ~MpiSession();  ///< MPI_Finalize
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  bool active() const { return active_; }
  int rank() const { return rank_; }
  int size() const { return size_; }

  /// True on every process when `ok` is true on every process (a collective: every process calls
  /// it at the same point). True at once without MPI.
  bool AllOk(bool ok) const;
  /// A collective that every process calls after work that may fail on some processes only (each
  /// reads its own copy of the scene): returns when `failure` is null on every process; otherwise
  /// every process throws, the error of the lowest failing rank (InputError, printed by rank 0 as
  /// the one line, naming that rank), so no process is left waiting in a later collective.
  /// Without MPI: rethrows `failure` when there is one.
  void ThrowIfAnyFailed(std::exception_ptr failure) const;
  /// A collective: every process gives its bytes; rank 0 gets them all, index = rank (its own
  /// included), the others get an empty vector. Any size (sent in pieces below 1 GiB).
  std::vector<std::string> GatherToRoot(const std::string& bytes) const;
  /// A collective: rank 0's `bytes` on every process (the others' arguments are ignored). Returns
  /// `bytes` at once without MPI.
  std::string Broadcast(const std::string& bytes) const;

 private:
  bool active_ = false;
  int rank_ = 0, size_ = 1;
};

/// True in a process of rank > 0 of an MPI run: it prints no errors (rank 0 prints the one line;
/// every rank meets the same input errors).
bool MpiQuietErrors();

/// Whether this build has MPI (CMake found it).
bool MpiAvailable();

}  // namespace pandora::app
