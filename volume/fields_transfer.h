#pragma once
/// \file fields_transfer.h
/// The fields of one partition of a distributed evaluation (FieldOptions::partition_count,
/// `pandora analyze --mpi`, docs/scale.md) as bytes, and their merge into another partition's: the
/// grids' leaves and tiles (the partitions' blocks are disjoint) and the statistics (counts summed,
/// histograms added, sigma lists joined). Merging every partition into partition 0's fields gives
/// the single-process fields voxel for voxel and the same statistics but for the timings. Light
/// header (no OpenVDB).

#include <string>

#include "volume/fields.h"

namespace pandora {

/// The grids (coverage, the float fields, the per-camera sets) and the statistics of `fields`.
std::string SerializePartialFields(const Fields& fields);

/// Adds the partition in `bytes` (SerializePartialFields of a partition of the same evaluation) to
/// `fields`: grids merged (voxels and tiles of `bytes` where `fields` has none), statistics added;
/// the active-set statistics and timings of `fields` stay. Throws std::runtime_error when the bytes
/// are not a partition of the same fields (other grids, camera count or lattice).
void MergePartialFields(const std::string& bytes, Fields* fields);

/// Adds the statistics of an evaluation of disjoint voxels (another partition, a streamed run's
/// tile) to `into`: the active set's counts, the seen, triangulable and unobservable voxels, the
/// tests, rays and triangulation_angle's pairs, the histogram and per-camera counts (the longer
/// length kept), the sigma lists joined, the times summed (the parts ran one after another), the
/// largest estimate kept.
void AddFieldStats(FieldStats* into, const FieldStats& part);

}  // namespace pandora
