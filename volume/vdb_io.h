#pragma once
/// \file vdb_io.h
/// Writing fields to a .vdb file (no OpenVDB in this header).

#include <map>
#include <string>

#include "volume/fields.h"

namespace pandora {

/// Writes every grid of `fields` to `path` (named grids, the world transform, and `metadata` attached
/// both to the file and to each grid, so `vdb_print -l` shows it). Writes `path` + ".tmp" first and
/// renames it, so `path` is never half written. Throws InputError (file = path) when the folder is not
/// writable.
void WriteFieldsVdb(const Fields& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata);

/// Reads a .vdb written by WriteFieldsVdb back into Fields (grids by name; the lattice's voxel size
/// and origin from the grids' transform; stats stay empty). Unknown grids are ignored. Throws
/// InputError (file = path) when the file cannot be read or holds none of the known grids.
Fields ReadFieldsVdb(const std::string& path);

/// Initializes OpenVDB's type registry (idempotent, thread-safe). Called by WriteFieldsVdb and
/// EvaluateFields; tools that read .vdb files call it first.
void InitializeOpenVdb();

}  // namespace pandora
