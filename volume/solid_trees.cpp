#include "volume/solid_trees.h"

#include <chrono>

#include "analysis/rig/rig_check.h"

namespace pandora {
namespace {

bool SameMesh(const TriangleMesh& a, const TriangleMesh& b) {
  return &a == &b || (a.vertices == b.vertices && a.triangles == b.triangles);
}

}  // namespace

SolidTrees::SolidTrees(const Scene& scene)
    : scene_(scene), once_(scene.objects.size() + 1), trees_(scene.objects.size() + 1) {}

SolidTrees::~SolidTrees() = default;

const InsideMesh* SolidTrees::Get(std::size_t slot, const TriangleMesh& mesh) const {
  std::call_once(once_[slot], [&] {
    const auto t0 = std::chrono::steady_clock::now();
    trees_[slot] = std::make_unique<InsideMesh>(mesh);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::lock_guard<std::mutex> lock(mutex_);
    ++built_;
    seconds_ += s;
  });
  return trees_[slot].get();
}

const InsideMesh* SolidTrees::Object(const Scene& scene, std::size_t index) const {
  if (index >= scene_.objects.size() || index >= scene.objects.size()) return nullptr;
  const SceneObject& mine = scene_.objects[index];
  if (!mine.solid || mine.mesh.triangles.empty() || !SameMesh(mine.mesh, scene.objects[index].mesh))
    return nullptr;
  return Get(index, mine.mesh);
}

const InsideMesh* SolidTrees::RegionMesh(const Scene& scene) const {
  const Region& mine = scene_.study.region;
  const Region& theirs = scene.study.region;
  if (mine.kind != Region::Kind::kMesh || theirs.kind != Region::Kind::kMesh ||
      mine.mesh.triangles.empty() || !SameMesh(mine.mesh, theirs.mesh))
    return nullptr;
  return Get(scene_.objects.size(), mine.mesh);
}

int SolidTrees::built() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return built_;
}

double SolidTrees::build_seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seconds_;
}

void SolidTrees::LendTo(const Scene& scene, RigCheckOptions* check) const {
  check->object_tree = [this, &scene](std::size_t o) { return Object(scene, o); };
  check->region_tree = [this, &scene] { return RegionMesh(scene); };
}

}  // namespace pandora
