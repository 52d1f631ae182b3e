// For the fuzz build: volume/vdb_io.cpp (with the writer and spilled leaves it uses) and the
// special members of Fields (as volume/fields.cpp defines them) in one translation unit, since each
// one that includes OpenVDB costs ~15 s. The fuzz targets read fields but never evaluate them, so
// they leave out fields.cpp and what it needs (CGAL, Embree, the visibility code). Never linked
// together with volume/fields.cpp.
#include "volume/leaf_spill.cpp"
#include "volume/vdb_io.cpp"
#include "volume/vdb_writer.cpp"

namespace pandora {

Fields::Fields() : impl_(std::make_unique<Impl>()) {}
Fields::~Fields() = default;
Fields::Fields(Fields&&) noexcept = default;
Fields& Fields::operator=(Fields&&) noexcept = default;

}  // namespace pandora
