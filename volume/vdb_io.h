#pragma once
/// \file vdb_io.h
/// Writing fields to a .vdb file and reading them back (no OpenVDB in this header). The file layout
/// is in docs/fields.md: every grid is a FloatGrid or a BoolGrid, so Debian's pyopenvdb reads it.

#include <map>
#include <string>

#include "volume/fields.h"
#include "volume/vdb_check.h"

namespace pandora {

/// Writes every grid of `fields` to `path`: the float fields under their names, "coverage" as a
/// FloatGrid of whole numbers (same active voxels and tiles as the Int32 grid in memory), and the
/// "cameras" bitmask as one BoolGrid per camera of the rig, named VisibilityGridName(id), active
/// and true where that camera sees the voxel, with int64 metadata "camera_index" and string
/// metadata "camera_id". Camera ids and the camera count come from the "rig" entry of `metadata`
/// (RigToJson, as `pandora analyze` passes it); without it cameras are named by their index. The
/// world transform and `metadata` are attached to the file and to each field grid (camera grids
/// get all of it but "rig"), so `vdb_print -l` shows it. Writes `path` + ".tmp" first and renames
/// it, so `path` is never half written. Throws InputError (file = path) when the folder is not
/// writable.
void WriteFieldsVdb(const Fields& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata);
/// The same file, consuming `fields` (what `pandora analyze` does last): the coverage grid becomes
/// floats leaf by leaf, each integer leaf freed as its copy is made, so writing does not hold a
/// second copy of it (docs/scale.md: 4 bytes per region voxel off the peak).
void WriteFieldsVdb(Fields&& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata);

/// Reads a .vdb written by WriteFieldsVdb back into Fields: exactly the grids that were written
/// (coverage back to Int32, the per-camera grids back to the Int64 bitmask; files of the earlier
/// layout with Int32 "coverage" and Int64 "cameras" grids are read as they are), the lattice's
/// voxel size and origin from the grids' transform and its dims from the active voxels' index box;
/// stats stay empty. Unknown grids are checked and ignored. The bytes are read once, checked by
/// CheckVdbBytes before OpenVDB parses anything, and parsed from memory (no delayed loading, no
/// memory mapping). When `provenance` is given it receives the file's metadata. Throws InputError
/// (file = path) when the file cannot be read, is not a regular file, is damaged in any way, holds
/// grids of an unexpected type or values out of range (coverage not a whole number of cameras in
/// [0, 64], a non-finite float field), grids with different transforms, or none of the known grids.
Fields ReadFieldsVdb(const std::string& path, FieldsProvenance* provenance = nullptr);

/// ReadFieldsVdb on bytes already in memory (`path` names them in messages); for fuzzing and tests.
Fields ReadFieldsVdbBytes(const std::string& bytes, const std::string& path,
                          FieldsProvenance* provenance = nullptr);

/// Initializes OpenVDB's type registry (idempotent, thread-safe). Called by WriteFieldsVdb and
/// EvaluateFields; tools that read .vdb files call it first.
void InitializeOpenVdb();

}  // namespace pandora
