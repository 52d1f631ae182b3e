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

/// Initializes OpenVDB's type registry (idempotent, thread-safe). Called by WriteFieldsVdb and
/// EvaluateFields; tools that read .vdb files call it first.
void InitializeOpenVdb();

}  // namespace pandora
