#pragma once
/// \file vdb_writer.h
/// Writes a .vdb file one grid at a time: each grid is made when its turn comes, written and
/// dropped before the next is made, so a file of many large grids needs the memory of one of them
/// beyond what the makers hold (fields.vdb: docs/performance.md, "All nine fields against coverage
/// alone"). The file is the one openvdb::io::File::write writes from the same grids (seekable, with
/// grid offsets; only the header's random UUID differs). Include only where OpenVDB is needed.

#include <openvdb/openvdb.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pandora {

/// One grid of the file: its name (the grid's own, as made) and how to make it.
struct GridToWrite {
  std::string name;
  std::function<openvdb::GridBase::Ptr()> make;
};

/// Writes `grids` in order, with the file-level `metadata`, `compression` (openvdb::io flags) and
/// grid statistics metadata, to `path` (created or truncated). Names used twice get OpenVDB's
/// "[n]" suffixes as io::File::write gives them. Trees shared between grids are written once per
/// grid (no instancing). Throws InputError(path, ...) when the file cannot be created or the write
/// fails (a full disk: the stream is checked, unlike io::File::write).
void WriteGridsOneAtATime(const std::string& path, const std::vector<GridToWrite>& grids,
                          const openvdb::MetaMap& metadata, std::uint32_t compression);

}  // namespace pandora
