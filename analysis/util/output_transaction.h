#pragma once
/// \file output_transaction.h
/// The outputs of one command appear together or not at all, and never replace an input.
///
/// Each output is written to a staging folder beside its final place (`.pandora-staging-PID-N`).
/// Commit() makes every staged file durable (fsync), then writes a journal listing them (the
/// commit point), then renames each into place and removes the staging folders. A process killed
/// before the commit point leaves the previous outputs untouched; one killed after it leaves a
/// journal, and the next Pandora command that writes in that folder or reads an output from it
/// finishes the renames first (RecoverOutputs). Stale staging folders and `*.tmp-PID` files of dead
/// processes are removed the same way. docs/robustness.md describes the guarantees and their
/// limits.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pandora {

class OutputTransaction {
 public:
  OutputTransaction();
  /// Abandons the transaction unless it was committed.
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// Registers a file the command reads: no output may resolve to it (the same file through any
  /// path, link or hard link). `what` names it in messages ("scene file").
  void AddInput(const std::string& path, const std::string& what);

  /// Declares the output `path` and returns the path to write it to (in a staging folder beside
  /// it). `option` names where the path came from, for messages ("--out"). Creates missing folders
  /// (removed again, if still empty, when the transaction does not commit) and sweeps what dead
  /// Pandora processes left there. When `path` exists, the staged file takes its mode and owner at
  /// Commit(); `mode_from` (when not empty) names another file whose mode and owner it takes
  /// instead. Throws InputError(option or path, "", ...) when `path` resolves to an input or to an
  /// output staged before, names a folder, or its folder cannot be created or written.
  std::string Stage(const std::string& path, const std::string& option,
                    const std::string& mode_from = "");

  /// Like Stage(), for the one output that deliberately replaces an input (`pandora accept`
  /// rewriting the scene file): `path` may be an input.
  std::string StageReplacement(const std::string& path, const std::string& option);

  /// Stage(path, option, mode_from), then writes `bytes` to the staged file (created with its final
  /// mode, every write checked). Throws InputError(path, ...) when writing fails (a full disk).
  void Write(const std::string& path, const std::string& option, const std::string& bytes,
             const std::string& mode_from = "");

  /// Declares that the existing regular file `path` (an output of an earlier run that this run does
  /// not write: a streamed run's surplus tiles) is removed when the outputs are committed, in the
  /// same transaction (journalled, so a run killed after the commit point still removes it). Does
  /// nothing when nothing is there; throws InputError when `path` is an input or not a regular
  /// file.
  void Remove(const std::string& path, const std::string& option);

  /// Makes every staged output appear at its final path. Throws InputError when a staged file is
  /// missing or empty, or when syncing or renaming fails before the commit point (nothing changed
  /// then); failures after it are finished by RecoverOutputs.
  void Commit();

  /// Removes the staged files and staging folders, and the folders Stage() created if empty.
  void Abandon() noexcept;

  /// An identifier of this transaction, unique across runs (hex); commands record it in every
  /// output so that a reader can tell whether two outputs come from the same run.
  const std::string& run_id() const { return run_id_; }

  /// The final paths staged so far, in order.
  std::vector<std::string> outputs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string run_id_;
};

/// Finishes or removes what killed Pandora processes left in `folder`: commits whose journal was
/// written are completed; other staging folders and `*.tmp-PID` files of dead processes are
/// removed. Never throws; does nothing when `folder` cannot be read.
void RecoverOutputs(const std::string& folder);

/// What `path` is when it exists and is not a regular file (links followed): "a character
/// device", "a folder", ...; empty when it is a regular file or nothing is there. Outputs are only
/// ever renamed over a regular file or nothing.
std::string NotARegularFile(const std::string& path);

/// Writes `bytes` to a new file `path` created with `mode` (umask applied), checking every write,
/// and flushes it to disk. On failure removes it and throws InputError(blame, ...).
void WriteNewFile(const std::string& path, const std::string& bytes, unsigned mode,
                  const std::string& blame);

/// Flushes `path` to disk (fsync) and checks that it is a regular file of at least `min_bytes`
/// bytes. Throws InputError(path, ...) otherwise.
void SyncFile(const std::string& path, std::uint64_t min_bytes = 1);

}  // namespace pandora
