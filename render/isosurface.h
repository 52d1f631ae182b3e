#pragma once
/// \file isosurface.h
/// The isosurface of a field as a triangle mesh, for front ends that draw it themselves (the
/// viewer's window). No OpenVDB here: the extraction lives in render/overlay_fields.cpp.

#include <string>

#include "analysis/geometry/geometry.h"

namespace pandora {

class Fields;

/// The surface value = `iso` of field `name` of `fields`, world coordinates, exactly the mesh the
/// renderer's isosurface overlay draws (OpenVDB volumeToMesh; inactive voxels never pass: outside
/// {value >= iso} for coverage-like fields, outside {value <= iso} for sigma_* and condition).
/// Throws InputError (file "{iso_field}") when the fields lack that grid.
TriangleMesh FieldIsosurface(const Fields& fields, const std::string& name, double iso);

}  // namespace pandora
