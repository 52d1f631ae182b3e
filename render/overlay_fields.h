#pragma once
/// \file overlay_fields.h
/// Internal to render/: what the renderer needs from the OpenVDB fields, without OpenVDB in the
/// header (overlay_fields.cpp is the only render file that includes OpenVDB).

#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "volume/slice.h"

namespace pandora {

class Fields;

/// The slice overlay of field `name` on the plane axis = position (NaN: the middle plane of the
/// field's active voxels): the voxel slice nearest the plane (volume/slice.h, empty where the plane
/// misses the fields) and, in *plane, the coordinate the plane is drawn at (`position`, or that
/// middle plane's). Throws InputError (file "{slice_field}") when the fields lack that grid.
FieldSlice SampleSlice(const Fields& fields, const std::string& name, int axis, double position,
                       double* plane);

/// The isosurface value = `iso` of field `name` (OpenVDB volumeToMesh, triangles and split quads),
/// world coordinates. Inactive voxels count as outside the set {value >= iso} for coverage-like
/// fields and as outside {value <= iso} for uncertainty fields (sigma_*, condition), i.e. they
/// never pass. Throws InputError (file "{iso_field}") when the fields lack that grid.
TriangleMesh ExtractIsosurface(const Fields& fields, const std::string& name, double iso);

}  // namespace pandora
