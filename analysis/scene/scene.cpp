#include "analysis/scene/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "analysis/geometry/pose.h"
#include "analysis/geometry/primitives.h"
#include "analysis/scene/builders.h"
#include "analysis/scene/mesh_io.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/allocation_budget.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/palette.h"
#include "analysis/util/sha256.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr int kMaxResolution = 65536;
constexpr int kMinSegments = 3;
constexpr int kMaxSegments = 4096;
constexpr int kDefaultSegments = 32;

// -------------------------------------------------------------------------------------------------
// Small string helpers.

std::string FormatNumber(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

// Five significant digits, for limits and distances in messages.
std::string Short(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.5g", v);
  return text;
}

// -------------------------------------------------------------------------------------------------
// Reading JSON with paths.

// What every reader needs: the file for messages, its folder for relative paths, the length unit.
struct Context {
  std::string file;
  fs::path folder;
  double metres_per_unit = 1.0;
  LoadOptions options;
};

// A scene file's JSON value with its path (analysis/util/json_reader.h), plus what a scene adds:
// lengths in the file's unit, the coordinate limit, colours and pixel noise.
class Node : public JsonNode {
 public:
  Node(const json* value, std::string path, const Context* context)
      : JsonNode(value, std::move(path), &context->file), context_(context) {}
  Node(const JsonNode& node, const Context* context) : JsonNode(node), context_(context) {}

  const Context& context() const { return *context_; }

  std::optional<Node> Find(const std::string& key) const {
    std::optional<JsonNode> child = JsonNode::Find(key);
    if (!child) return std::nullopt;
    return Node(*child, context_);
  }
  Node Get(const std::string& key) const { return Node(JsonNode::Get(key), context_); }
  Node At(size_t i) const { return Node(JsonNode::At(i), context_); }

  // A pixel noise sigma: positive and within [1e-6, 1e6] pixels, so 1 / sigma^2 stays a normal
  // double in any information matrix.
  double PixelSigma() const {
    const double v = Positive();
    if (v < 1e-6 || v > 1e6)
      Fail("pixel noise must be between 1e-6 and 1e6 pixels, got " + FormatNumber(v));
    return v;
  }

  // A length in the file's unit, returned in metres. Length() is not bounded (a camera's far
  // range may be astronomical); the others are within SceneLimits::kMaxCoordinate.
  double Length() const { return Number() * context_->metres_per_unit; }
  double PositiveLength() const { return Bounded(Positive() * context_->metres_per_unit); }
  double NonNegativeLength() const { return Bounded(NonNegative() * context_->metres_per_unit); }

  // `metres`, after checking it is within SceneLimits::kMaxCoordinate.
  double Bounded(double metres) const {
    if (!(std::abs(metres) <= SceneLimits::kMaxCoordinate))
      Fail(Short(metres) + " m is beyond the limit of " + Short(SceneLimits::kMaxCoordinate) +
               " m on coordinates and lengths",
           "check the number and the file's \"units\"");
    return metres;
  }

  Vec3 Vector3() const { return Numbers(3); }
  Vec2 Vector2() const { return Numbers(2); }
  Vec3 Point() const {
    const Vec3 p = Vector3() * context_->metres_per_unit;
    for (int i = 0; i < 3; ++i) At(i).Bounded(p[i]);
    return p;
  }

  Vec3 PositiveVector3() const {
    Vec3 v = Vector3();
    for (int i = 0; i < 3; ++i) {
      if (!(v[i] > 0)) At(i).Fail("must be positive, got " + FormatNumber(v[i]));
    }
    return v;
  }

  // [r, g, b] linear in [0, 1], or "#rrggbb" in sRGB (converted to linear).
  Vec3 Color() const {
    if (value().is_string()) {
      const std::string s = value().get<std::string>();
      const bool ok =
          s.size() == 7 && s[0] == '#' && std::all_of(s.begin() + 1, s.end(), [](char c) {
            return std::isxdigit(static_cast<unsigned char>(c));
          });
      if (!ok) Fail("expected a colour \"#rrggbb\", got " + json(s).dump());
      Vec3 color;
      for (int i = 0; i < 3; ++i)
        color[i] = LinearFromSrgb(std::stoi(s.substr(1 + 2 * i, 2), nullptr, 16) / 255.0);
      return color;
    }
    if (!value().is_array()) {
      Fail("expected a colour: [r, g, b] with components in 0..1 or \"#rrggbb\", got " +
           TypeName());
    }
    const Vec3 color = Vector3();
    for (int i = 0; i < 3; ++i) {
      if (color[i] < 0 || color[i] > 1) {
        At(i).Fail("colour components must be in 0..1, got " + FormatNumber(color[i]));
      }
    }
    return color;
  }

 private:
  const Context* context_;
};

// -------------------------------------------------------------------------------------------------
// Scene parts.

Mat3 RotationXyzDegrees(const Vec3& degrees) {
  return (Eigen::AngleAxisd(degrees.z() * kRadPerDeg, Vec3::UnitZ()) *
          Eigen::AngleAxisd(degrees.y() * kRadPerDeg, Vec3::UnitY()) *
          Eigen::AngleAxisd(degrees.x() * kRadPerDeg, Vec3::UnitX()))
      .toRotationMatrix();
}

// [w, x, y, z], normalized.
Mat3 ReadQuaternion(const Node& node) {
  const Eigen::VectorXd q = node.Numbers(4);
  const double norm = q.norm();
  if (!(norm > 1e-9)) node.Fail("quaternion is zero (its length must not be close to 0)");
  return Eigen::Quaterniond(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm).toRotationMatrix();
}

// Rotation that turns a Y-up model into this Z-up world: (x, y, z) -> (x, -z, y).
Mat3 YUpToZUp() {
  Mat3 m;
  m << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return m;
}

std::string Extension(const std::string& file) {
  std::string ext = fs::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string ResolvePath(const Context& context, const std::string& file) {
  const fs::path p(file);
  return p.is_absolute() ? p.string() : (context.folder / p).lexically_normal().string();
}

// A "mesh" block ({"file", "unit_scale", "up_axis"}), read but not loaded.
struct MeshReference {
  std::string file;                // As written.
  std::string resolved;            // Against the scene's folder.
  Node file_node;                  // For errors.
  Eigen::Affine3d file_to_object;  // Unit scale and up-axis conversion, to metres.
};

MeshReference ReadMeshReference(const Node& node) {
  node.CheckKeys({"file", "unit_scale", "up_axis"});
  const Node file_node = node.Get("file");
  const std::string file = file_node.NonEmptyString();
  double unit_scale = 1.0;
  if (auto n = node.Find("unit_scale")) unit_scale = n->Positive();
  const std::string ext = Extension(file);
  // glTF is Y-up by definition; assimp converts COLLADA to Y-up whatever the file declares.
  std::string up_axis = (ext == ".gltf" || ext == ".glb" || ext == ".dae") ? "y" : "z";
  if (auto n = node.Find("up_axis")) {
    up_axis = n->String();
    if (up_axis != "y" && up_axis != "z") {
      n->Fail("unknown up axis " + json(up_axis).dump(), "use \"z\" or \"y\"");
    }
  }
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();
  if (up_axis == "y") transform.linear() = YUpToZUp();
  transform.linear() *= unit_scale * node.context().metres_per_unit;
  return MeshReference{file, ResolvePath(node.context(), file), file_node, transform};
}

// Loads the parts of a mesh file, rethrowing its errors at the "file" field.
std::vector<MeshPart> LoadMeshParts(const MeshReference& reference) {
  try {
    return LoadMeshFile(reference.resolved);
  } catch (const InputError& e) {
    reference.file_node.Fail(e.reason() + " (" + reference.resolved + ")", e.hint());
  }
}

// Loads a mesh file with its bones and clips, rethrowing its errors at the "file" field.
SkinnedMeshFile LoadSkinnedParts(const MeshReference& reference) {
  try {
    return LoadSkinnedMeshFile(reference.resolved);
  } catch (const InputError& e) {
    reference.file_node.Fail(e.reason() + " (" + reference.resolved + ")", e.hint());
  }
}

// "animation": {"clip", "speed", "offset_s", "loop"}: everything but the clip, which needs the
// file.
SkinnedObject ReadAnimation(const Node& node) {
  node.CheckKeys({"clip", "speed", "offset_s", "loop"});
  SkinnedObject skin;
  if (auto n = node.Find("clip")) {
    if (n->value().is_string())
      n->NonEmptyString();
    else if (n->value().is_number())
      n->Integer(0, 1000000);
    else
      n->Fail("expected a clip name or index, got " + n->TypeName(),
              "give the clip's name, e.g. \"walk\", or its index");
  }
  if (auto n = node.Find("speed")) {
    skin.speed = n->Positive();
    if (!(skin.speed <= 1000)) n->Fail("expected a speed in (0, 1000] clip seconds per second");
  }
  if (auto n = node.Find("offset_s")) {
    skin.offset_s = n->Number();
    if (!std::isfinite(skin.offset_s) || std::abs(skin.offset_s) > 1e9)
      n->Fail("expected a time in seconds within 1e9");
  }
  if (auto n = node.Find("loop")) skin.loop = n->Bool();
  return skin;
}

// The clip "animation"."clip" names in `skeleton` (by name, or index); the only clip when none is
// named.
int ResolveClip(const Node& node, const Skeleton& skeleton) {
  const int count = int(skeleton.clips.size());
  const auto n = node.Find("clip");
  if (!n) {
    if (count == 1) return 0;
    node.Fail(
        "the mesh file has " + std::to_string(count) + " animation clips; name one with \"clip\"",
        "the clips: " + skeleton.ClipList());
  }
  if (n->value().is_number()) {
    const int index = n->Integer(0, 1000000);
    if (index >= count)
      n->Fail("no clip " + std::to_string(index) + ": the mesh file has " + std::to_string(count),
              "the clips: " + skeleton.ClipList());
    return index;
  }
  const std::string name = n->NonEmptyString();
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) {
    if (skeleton.clips[i].name == name) return i;
    if (!skeleton.clips[i].name.empty()) names.push_back(skeleton.clips[i].name);
  }
  n->Fail("no clip " + Quoted(name) + " in the mesh file",
          names.size() == std::size_t(count) ? DidYouMean(name, names, "clips in this file")
                                             : "the clips: " + skeleton.ClipList());
}

TriangleMesh Transformed(const TriangleMesh& mesh, const Eigen::Affine3d& transform) {
  TriangleMesh out = mesh;
  for (Vec3& v : out.vertices) v = transform * v;
  return out;
}

// Fails unless `mesh` is closed and oriented outward. `subject` names it in messages.
void CheckSolid(const TriangleMesh& mesh, const Node& node, const std::string& subject,
                const std::string& fix) {
  const TriangleMesh welded = WeldVertices(mesh);
  const ClosedCheck check = CheckClosed(welded);
  if (!check.closed) {
    std::ostringstream reason;
    reason << subject << " must be closed, but " << check.description << "; " << check.bad_edges
           << " bad edge(s), e.g. from (" << check.example_a.transpose() << ") to ("
           << check.example_b.transpose() << ")";
    node.Fail(reason.str(),
              "a closed mesh shares every edge between exactly two triangles of opposite "
              "orientation; " +
                  fix);
  }
  const double volume = SignedVolume(welded);
  if (!(volume > 0)) {
    node.Fail(subject + " must face outward, but its triangles face inward (signed volume " +
                  FormatNumber(volume) + " m^3)",
              "flip the normals of the mesh in a modelling tool");
  }
}

// Adds a material, returning its index.
int AddMaterial(Scene* scene, Material material) {
  scene->materials.push_back(std::move(material));
  return static_cast<int>(scene->materials.size()) - 1;
}

Material ReadMaterial(const Node& node, const std::string& name) {
  node.CheckKeys({"color", "texture"});
  Material material;
  material.name = name;
  if (auto n = node.Find("color")) material.color = n->Color();
  if (auto n = node.Find("texture")) {
    material.texture = ResolvePath(node.context(), n->NonEmptyString());
  }
  return material;
}

// Fails when a vertex of an object (after its unit, scale and transform) lies beyond
// SceneLimits::kMaxCoordinate.
void CheckObjectBounds(const TriangleMesh& mesh, const Node& node) {
  const Aabb b = mesh.Bounds();
  if (b.empty()) return;
  const double reach = std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
  if (!(reach <= SceneLimits::kMaxCoordinate))
    node.Fail("the object reaches " + Short(reach) + " m from the origin, beyond the limit of " +
                  Short(SceneLimits::kMaxCoordinate) + " m",
              "check its scale, its unit_scale and the file's \"units\"");
}

// An object's instance transform: translate * rotate * scale, in metres.
Eigen::Affine3d ReadObjectTransform(const Node& node) {
  Vec3 position = Vec3::Zero();
  if (auto n = node.Find("position")) position = n->Point();
  Mat3 rotation = Mat3::Identity();
  if (node.Has("rotation_deg") && node.Has("quaternion")) {
    node.Get("quaternion")
        .Fail("both 'rotation_deg' and 'quaternion' are given", "give one rotation form");
  }
  if (auto n = node.Find("rotation_deg")) rotation = RotationXyzDegrees(n->Vector3());
  if (auto n = node.Find("quaternion")) rotation = ReadQuaternion(*n);
  Vec3 scale = Vec3::Ones();
  if (auto n = node.Find("scale")) {
    scale = n->value().is_number() ? Vec3::Constant(n->Positive()) : n->PositiveVector3();
  }
  Eigen::Affine3d world_from_object = Eigen::Affine3d::Identity();
  world_from_object.translation() = position;
  world_from_object.linear() = rotation * scale.asDiagonal();
  return world_from_object;
}

// An object's material index: a named one, a colour shortcut, or -1 (meshes: the file's own).
int ReadObjectMaterial(const Node& node, const std::map<std::string, int>& material_index,
                       const std::string& name, Scene* scene) {
  int material = -1;
  if (node.Has("material") && node.Has("color")) {
    node.Get("color").Fail("both 'material' and 'color' are given", "give one of them");
  }
  if (auto n = node.Find("material")) {
    const std::string material_name = n->NonEmptyString();
    const auto it = material_index.find(material_name);
    if (it == material_index.end()) {
      std::vector<std::string> known;
      for (const auto& [k, v] : material_index) known.push_back(k);
      n->Fail("unknown material " + Quoted(material_name),
              known.empty() ? "define it under \"materials\""
                            : DidYouMean(material_name, known, "defined materials"));
    }
    material = it->second;
  }
  if (auto n = node.Find("color")) {
    Material m;
    m.name = name;
    m.color = n->Color();
    material = AddMaterial(scene, m);
  }
  return material;
}

// Adds the objects of a "mesh" entry (one per part of the file), skinned when animated.
void AddMeshObjects(const Node& node, const Node& geometry, const std::optional<Node>& animation,
                    const std::string& name, const Eigen::Affine3d& world_from_object, int material,
                    bool solid, const Context& context, Scene* scene) {
  const MeshReference reference = ReadMeshReference(geometry);
  const Eigen::Affine3d transform = world_from_object * reference.file_to_object;
  std::optional<SkinnedObject> skin;
  if (animation) skin = ReadAnimation(*animation);
  if (!context.options.load_meshes) {
    scene->objects.push_back(
        {name, reference.file, TriangleMesh(), material, solid, {}, -1, std::nullopt});
    if (skin) {  // no skeleton: the object stays as placed
      skin->object = int(scene->objects.size()) - 1;
      scene->objects.back().skin = int(scene->skins.size());
      scene->skins.push_back(*skin);
    }
    return;
  }
  std::vector<MeshPart> parts;
  SkinnedMeshFile skinned;
  if (skin) {
    skinned = LoadSkinnedParts(reference);
    skin->skeleton = skinned.skeleton;
    skin->world_from_file = transform;
    skin->clip = ResolveClip(*animation, *skinned.skeleton);
    parts = skinned.parts;
  } else {
    parts = LoadMeshParts(reference);
  }
  TriangleMesh all;
  std::set<std::string> part_names;
  for (MeshPart& part : parts) {
    SceneObject object;
    object.name = name;
    if (parts.size() > 1) {
      object.name = name + "/" + part.material_name;
      for (int k = 2; !part_names.insert(object.name).second; ++k) {
        object.name = name + "/" + part.material_name + "#" + std::to_string(k);
      }
    }
    object.source = reference.file;
    object.mesh = Transformed(part.mesh, transform);
    CheckObjectBounds(object.mesh, node);
    object.solid = solid;
    object.material = material;
    if (material < 0 && part.has_material) {
      object.material = AddMaterial(
          scene, Material{name + "/" + part.material_name, part.color, part.texture, nullptr});
    }
    if (solid) all.Append(object.mesh);
    if (skin) {
      SkinnedObject part_skin = *skin;
      part_skin.object = int(scene->objects.size());
      part_skin.binding = skinned.bindings[std::size_t(&part - parts.data())];
      object.skin = int(scene->skins.size());
      scene->skins.push_back(std::move(part_skin));
    }
    scene->objects.push_back(std::move(object));
  }
  if (solid) {
    CheckSolid(all, node, "solid object " + Quoted(name),
               "repair the mesh, or set \"solid\": false");
  }
}

// The mesh of a primitive object ("box", "sphere", "cylinder", "capsule", "plane"), unplaced.
TriangleMesh MakePrimitive(const std::string& kind, const Node& geometry, double unit) {
  auto segments = [&geometry]() {
    auto n = geometry.Find("segments");
    return n ? n->Integer(kMinSegments, kMaxSegments) : kDefaultSegments;
  };
  TriangleMesh mesh;
  if (kind == "box") {
    geometry.CheckKeys({"size"});
    mesh = MakeBox(geometry.Get("size").PositiveVector3() * unit);
  } else if (kind == "sphere") {
    geometry.CheckKeys({"radius", "segments"});
    mesh = MakeSphere(geometry.Get("radius").PositiveLength(), segments());
  } else if (kind == "cylinder") {
    geometry.CheckKeys({"radius", "height", "segments"});
    mesh = MakeCylinder(geometry.Get("radius").PositiveLength(),
                        geometry.Get("height").PositiveLength(), segments());
  } else if (kind == "capsule") {
    geometry.CheckKeys({"radius", "length", "segments"});
    mesh = MakeCapsule(geometry.Get("radius").PositiveLength(),
                       geometry.Get("length").NonNegativeLength(), segments());
  } else {  // plane
    geometry.CheckKeys({"size"});
    const Node size_node = geometry.Get("size");
    const Vec2 size = size_node.Vector2();
    for (int i = 0; i < 2; ++i) {
      if (!(size[i] > 0)) size_node.At(i).Fail("must be positive, got " + FormatNumber(size[i]));
    }
    mesh = MakePlane(size * unit);
  }
  return mesh;
}

// A "marker" or "board" object's fiducial (analysis/scene/fiducial.h), checked.
Fiducial ReadFiducial(const std::string& kind, const Node& geometry, const std::string& name) {
  Fiducial f;
  f.name = name;
  auto dictionary = [&](const char* fallback) {
    const std::optional<Node> n = geometry.Find("dictionary");
    f.dictionary = n ? n->NonEmptyString() : std::string(fallback);
    const ArucoDictionaryInfo* d = FindArucoDictionary(f.dictionary);
    if (!d)
      (n ? *n : geometry)
          .Fail("unknown ArUco dictionary " + Quoted(f.dictionary),
                DidYouMean(f.dictionary, ArucoDictionaryNames(), "OpenCV's dictionaries"));
    return d;
  };
  auto length = [&](const char* key, double fallback) {
    const std::optional<Node> n = geometry.Find(key);
    return n ? n->NonNegativeLength() : fallback;
  };
  if (kind == "marker") {
    geometry.CheckKeys({"dictionary", "id", "size", "margin", "thickness"});
    f.kind = Fiducial::Kind::kMarker;
    const ArucoDictionaryInfo* d = dictionary("DICT_4X4_50");
    const Node id = geometry.Get("id");
    f.id = id.Integer(0, d->size - 1);
    f.square_m = geometry.Get("size").PositiveLength();
    f.margin_m = length("margin", f.square_m / (d->bits + 2));
  } else {
    geometry.CheckKeys(
        {"type", "squares", "square", "marker", "dictionary", "first_id", "margin", "thickness"});
    const std::string type = geometry.Get("type").Enum({"charuco", "checkerboard"});
    f.kind = type == "charuco" ? Fiducial::Kind::kCharuco : Fiducial::Kind::kCheckerboard;
    const Node squares = geometry.Get("squares");
    if (squares.ArraySize("an array of 2 integers [x, y]") != 2)
      squares.Fail("expected an array of 2 integers [x, y]");
    f.squares_x = squares.At(0).Integer(2, 100);
    f.squares_y = squares.At(1).Integer(2, 100);
    f.square_m = geometry.Get("square").PositiveLength();
    f.margin_m = length("margin", 0.5 * f.square_m);
    if (f.kind == Fiducial::Kind::kCharuco) {
      const ArucoDictionaryInfo* d = dictionary("DICT_4X4_50");
      f.marker_m = length("marker", 0.75 * f.square_m);
      if (!(f.marker_m > 0 && f.marker_m < f.square_m))
        geometry.Get("marker").Fail("a ChArUco marker must be smaller than its square (" +
                                    FormatNumber(f.square_m) + " m) and positive");
      if (auto n = geometry.Find("first_id")) f.id = n->Integer(0, d->size - 1);
      if (f.id + f.Markers() > d->size)
        geometry.Fail("the board needs " + std::to_string(f.Markers()) + " markers from id " +
                          std::to_string(f.id) + ", but " + f.dictionary + " has " +
                          std::to_string(d->size),
                      "use fewer squares, a lower first_id or a larger dictionary");
    } else {
      for (const char* key : {"marker", "dictionary", "first_id"})
        if (geometry.Has(key))
          geometry.Get(key).Fail(std::string("a checkerboard has no markers: '") + key +
                                 "' is for \"type\": \"charuco\"");
    }
  }
  f.thickness_m = length("thickness", 0.003);
  f.margin_m = f.MarginTexels() / f.TexelsPerMetre();  // whole texels
  int tw = 0, th = 0;
  FiducialTextureSize(f, &tw, &th);
  if (tw > 8192 || th > 8192)
    geometry.Fail("its print would be " + std::to_string(tw) + " x " + std::to_string(th) +
                      " texels (12 per marker cell), more than 8192",
                  "use a smaller margin or larger markers");
  return f;
}

// Adds a "marker" or "board" object: the sheet (analysis/scene/fiducial.h) placed by the object's
// pose, its own white material for the print, and the fiducial. The group is set by the caller.
void AddFiducialObject(const Node& node, const std::string& kind, const std::string& name,
                       Scene* scene) {
  for (const char* key : {"scale", "material", "color", "solid", "animation"})
    if (node.Has(key))
      node.Get(key).Fail(std::string("'") + key + "' does not apply to a printed " + kind,
                         "its size and print are given in \"" + kind + "\"");
  const Fiducial f = ReadFiducial(kind, node.Get(kind), name);
  for (const Fiducial& other : scene->fiducials) {  // a detector could not tell them apart
    if (f.kind == Fiducial::Kind::kCheckerboard || other.kind == Fiducial::Kind::kCheckerboard ||
        f.dictionary != other.dictionary)
      continue;
    const int lo = std::max(f.id, other.id);
    const int hi = std::min(f.id + f.Markers(), other.id + other.Markers());
    if (lo < hi)
      node.Get(kind).Fail("marker id " + std::to_string(lo) + " of " + f.dictionary +
                              " is also printed on " + Quoted(other.name),
                          "give each printed marker its own id");
  }
  AddFiducial(scene, f, ReadObjectTransform(node));
  CheckObjectBounds(scene->objects.back().mesh, node);
}

// ---- Rooms, furniture and people (analysis/scene/builders.h).

// A 2D point list [[x, y], ...] in the file's unit.
Polygon2 ReadPolygon(const Node& node, std::size_t max_points) {
  const std::size_t n = node.ArraySize(max_points, "an array of [x, y] points");
  Polygon2 out;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 v = node.At(i).Vector2() * node.context().metres_per_unit;
    for (int k = 0; k < 2; ++k) node.At(i).At(k).Bounded(v[k]);
    out.push_back(v);
  }
  return out;
}

// "openings": [{"wall", "type": "door" | "window", "offset", "width", "height", "sill"}].
WallOpening ReadOpening(const Node& node) {
  node.CheckKeys({"wall", "type", "offset", "width", "height", "sill"});
  WallOpening o;
  const std::string type = node.Has("type") ? node.Get("type").Enum({"door", "window"}) : "door";
  if (type == "window") o.width = 1.2, o.height = 1.2, o.sill = 0.9;
  o.wall = node.Get("wall").Integer(0, 100000);
  o.offset = node.Get("offset").NonNegativeLength();
  if (auto n = node.Find("width")) o.width = n->PositiveLength();
  if (auto n = node.Find("height")) o.height = n->PositiveLength();
  if (auto n = node.Find("sill")) o.sill = n->NonNegativeLength();
  if (type == "door" && node.Has("sill") && o.sill > 0)
    node.Get("sill").Fail("a door starts at the floor", "give \"type\": \"window\" for a sill");
  return o;
}

void AddPart(Scene* scene, const std::string& name, const std::string& source, TriangleMesh mesh,
             const Eigen::Affine3d& transform, int material, bool solid, const Node& node) {
  SceneObject object;
  object.name = name;
  object.source = source;
  object.mesh = Transformed(mesh, transform);
  object.material = material;
  object.solid = solid;
  CheckObjectBounds(object.mesh, node);
  scene->objects.push_back(std::move(object));
}

// "furniture": [{"type", "name", "at": [x, y], "yaw_deg", "size", "color"}]: solid boxes on the
// floor, named ROOM/NAME (NAME: the name, else the type, numbered when repeated).
void AddFurniture(const Node& list, const std::string& room, const Eigen::Affine3d& transform,
                  int material, std::set<std::string>* names, Scene* scene) {
  const std::size_t n = list.ArraySize(10000, "an array of furniture");
  for (std::size_t i = 0; i < n; ++i) {
    const Node f = list.At(i);
    f.CheckKeys({"type", "name", "at", "yaw_deg", "size", "color", "solid"});
    Vec3 size;
    std::string type;
    if (auto t = f.Find("type")) {
      type = t->NonEmptyString();
      if (!FurnitureSize(type, &size))
        t->Fail("unknown furniture type " + Quoted(type),
                DidYouMean(type, FurnitureTypes(), "furniture types") +
                    "; or give \"size\": [x, y, height]");
    } else if (!f.Has("size")) {
      f.Fail("furniture needs a \"type\" or a \"size\"",
             "known types: " + JoinQuoted(FurnitureTypes()));
    }
    if (auto s = f.Find("size")) size = s->PositiveVector3() * f.context().metres_per_unit;
    std::string name = f.Has("name") ? f.Get("name").NonEmptyString() : type;
    if (name.empty()) name = "box";
    std::string full = room + "/" + name;
    for (int k = 2; names->count(full); ++k) {
      if (f.Has("name")) f.Get("name").Fail("duplicate furniture name " + Quoted(name));
      full = room + "/" + name + std::to_string(k);
    }
    names->insert(full);
    const Vec2 at = f.Get("at").Vector2() * f.context().metres_per_unit;
    const double yaw = f.Has("yaw_deg") ? f.Get("yaw_deg").Number(-36000, 36000) : 0.0;
    Eigen::Affine3d place = Eigen::Affine3d::Identity();
    place.translation() = Vec3(at.x(), at.y(), 0.5 * size.z());
    place.linear() = RotationXyzDegrees(Vec3(0, 0, yaw));
    int m = material;
    if (auto c = f.Find("color")) m = AddMaterial(scene, Material{full, c->Color(), "", nullptr});
    const bool solid = f.Has("solid") ? f.Get("solid").Bool() : true;
    AddPart(scene, full, "furniture", MakeBox(size), transform * place, m, solid, f);
  }
}

// A "room" entry: walls round a footprint with openings, floor, ceiling, furniture.
void AddRoomObjects(const Node& node, const Node& geometry, const std::string& name,
                    const Eigen::Affine3d& transform, int material, bool solid,
                    std::set<std::string>* names, Scene* scene) {
  geometry.CheckKeys({"footprint", "height", "wall_thickness", "slab", "floor", "ceiling",
                      "openings", "furniture"});
  RoomSpec room;
  room.footprint = ReadPolygon(geometry.Get("footprint"), 10000);
  if (auto n = geometry.Find("height")) room.height = n->PositiveLength();
  if (auto n = geometry.Find("wall_thickness")) room.thickness = n->PositiveLength();
  if (auto n = geometry.Find("slab")) room.slab = n->PositiveLength();
  if (auto n = geometry.Find("floor")) room.floor = n->Bool();
  if (auto n = geometry.Find("ceiling")) room.ceiling = n->Bool();
  std::optional<Node> openings = geometry.Find("openings");
  if (openings) {
    const std::size_t n = openings->ArraySize(10000, "an array of openings");
    for (std::size_t i = 0; i < n; ++i) room.openings.push_back(ReadOpening(openings->At(i)));
  }
  int bad_opening = -1;
  const std::string problem = RoomProblem(room, &bad_opening);
  if (!problem.empty()) {
    if (bad_opening >= 0) openings->At(std::size_t(bad_opening)).Fail(problem);
    const bool outer = problem.rfind("footprint", 0) != 0;
    geometry.Get(outer ? "wall_thickness" : "footprint")
        .Fail(problem, outer ? "thinner walls, or a footprint with fewer narrow spots"
                             : "list the corners in order round the room");
  }
  for (BuiltPart& part : BuildRoom(room)) {
    names->insert(name + "/" + part.name);
    AddPart(scene, name + "/" + part.name, "room", std::move(part.mesh), transform, material, solid,
            node);
  }
  if (auto f = geometry.Find("furniture"))
    AddFurniture(*f, name, transform, material, names, scene);
}

// An "extrusion": {"polygon": [[x, y], ...], "height"}: the prism of a simple polygon from z = 0.
TriangleMesh ReadExtrusion(const Node& geometry) {
  geometry.CheckKeys({"polygon", "height"});
  const Polygon2 polygon = ReadPolygon(geometry.Get("polygon"), 100000);
  const std::string problem = PolygonProblem(polygon);
  if (!problem.empty())
    geometry.Get("polygon").Fail(problem, "list the outline's corners in order round it");
  return ExtrudePolygon(polygon, 0, geometry.Get("height").PositiveLength());
}

// A "person" entry: an articulated figure of capsules, feet at the object's position, facing the
// object's +x.
void AddPersonObjects(const Node& geometry, const std::string& name,
                      const Eigen::Affine3d& transform, int material, bool solid, Scene* scene) {
  geometry.CheckKeys({"height", "pose", "girth", "segments"});
  PersonSpec spec;
  if (auto n = geometry.Find("height")) {
    spec.height = n->PositiveLength();
    if (spec.height < 0.5 || spec.height > 2.5)
      n->Fail("a person's height must be 0.5 to 2.5 m, got " + Short(spec.height) + " m");
  }
  if (auto n = geometry.Find("pose")) spec.pose = n->Enum(PersonPoses());
  if (auto n = geometry.Find("girth")) spec.girth = n->Number(0.5, 2.0);
  if (auto n = geometry.Find("segments")) spec.segments = n->Integer(kMinSegments, 64);
  Scene::Person person;
  person.name = name;
  person.pose = spec.pose;
  person.height = spec.height;
  const Vec3 forward = transform.linear() * Vec3::UnitX();
  person.facing_deg = std::atan2(forward.y(), forward.x()) * 180.0 / M_PI;
  for (BuiltPart& part : BuildPerson(spec)) {
    SceneObject object;
    object.name = name + "/" + part.name;
    object.source = "person";
    object.mesh = Transformed(part.mesh, transform);
    object.material = material;
    object.solid = solid;
    object.capsule =
        SceneObject::CapsuleAxis{transform * part.axis_a, transform * part.axis_b, part.radius};
    CheckObjectBounds(object.mesh, geometry);
    person.objects.push_back(int(scene->objects.size()));
    scene->objects.push_back(std::move(object));
  }
  scene->people.push_back(std::move(person));
}

void ReadObject(const Node& node, const std::map<std::string, int>& material_index,
                std::set<std::string>* names, Scene* scene) {
  const std::vector<std::string> geometry_keys = {"box",   "sphere", "cylinder", "capsule",
                                                  "plane", "mesh",   "marker",   "board",
                                                  "room",  "person", "extrusion"};
  std::vector<std::string> allowed = {"name",  "position", "rotation_deg", "quaternion",
                                      "scale", "material", "color",        "solid",
                                      "group", "animation"};
  allowed.insert(allowed.end(), geometry_keys.begin(), geometry_keys.end());
  node.CheckKeys(allowed);

  const Node name_node = node.Get("name");
  const std::string name = name_node.NonEmptyString();
  if (!names->insert(name).second) {
    name_node.Fail("duplicate object name " + Quoted(name), "object names must be unique");
  }
  const std::string kind = node.OneOf(geometry_keys, "geometry key");
  const Node geometry = node.Get(kind);
  std::string group;
  if (auto n = node.Find("group")) group = n->NonEmptyString();
  const std::size_t first_object = scene->objects.size();
  // Every object this entry adds (a mesh file's parts too) belongs to the group.
  struct GroupAssign {
    Scene* scene;
    std::size_t first;
    const std::string& group;
    ~GroupAssign() {
      for (std::size_t o = first; o < scene->objects.size(); ++o) scene->objects[o].group = group;
    }
  } assign{scene, first_object, group};

  if (kind == "marker" || kind == "board") {
    AddFiducialObject(node, kind, name, scene);
    return;
  }
  const bool built = kind == "room" || kind == "person";
  if (built && node.Has("scale"))
    node.Get("scale").Fail("a " + kind + " is sized by its own keys, not scaled",
                           kind == "room" ? "give the footprint and height in the file's units"
                                          : "give \"height\" (and \"girth\")");
  const Eigen::Affine3d world_from_object = ReadObjectTransform(node);

  // Rooms and people are solid unless told otherwise (their parts are closed by construction).
  bool solid = built;
  if (auto n = node.Find("solid")) {
    solid = n->Bool();
    if (solid && kind == "plane") n->Fail("a plane is an open sheet and cannot be solid");
  }

  const int material = ReadObjectMaterial(node, material_index, name, scene);
  if (kind == "room") {
    if (node.Has("animation")) node.Get("animation").Fail("a room has no animation");
    AddRoomObjects(node, geometry, name, world_from_object, material, solid, names, scene);
    return;
  }
  if (kind == "person") {
    if (node.Has("animation"))
      node.Get("animation")
          .Fail("a person's motion is given under \"motions\"",
                "\"walk\" or \"wander\" in \"motions\" (docs/scene-format.md)");
    AddPersonObjects(geometry, name, world_from_object, material, solid, scene);
    return;
  }

  const Context& context = node.context();
  const double unit = context.metres_per_unit;

  const std::optional<Node> animation = node.Find("animation");
  if (animation && kind != "mesh")
    animation->Fail(
        "\"animation\" needs a mesh file with bones and an animation clip, not a " + kind,
        "give \"mesh\": {\"file\": ...} with a glTF, FBX or COLLADA file, or remove \"animation\"");
  if (kind == "mesh") {
    AddMeshObjects(node, geometry, animation, name, world_from_object, material, solid, context,
                   scene);
    return;
  }

  const TriangleMesh mesh =
      kind == "extrusion" ? ReadExtrusion(geometry) : MakePrimitive(kind, geometry, unit);
  scene->objects.push_back(
      {name, kind, Transformed(mesh, world_from_object), material, solid, {}, -1, std::nullopt});
  CheckObjectBounds(scene->objects.back().mesh, node);
  // Primitives are closed by construction; the check guards against degenerate transforms.
  if (solid) {
    CheckSolid(scene->objects.back().mesh, node, "solid object " + Quoted(name),
               "set \"solid\": false");
  }
}

// Pose: "position" plus one of "look_at" (+ "up"), "quaternion", "euler_deg".
Eigen::Isometry3d ReadPose(const Node& node) {
  const Vec3 position = node.Get("position").Point();
  const std::string form = node.OneOf({"look_at", "quaternion", "euler_deg"}, "orientation");
  if (form != "look_at" && node.Has("up")) {
    node.Get("up").Fail("'up' only applies with 'look_at'");
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = position;
  if (form == "look_at") {
    const Node target_node = node.Get("look_at");
    const Vec3 target = target_node.Point();
    Vec3 up = Vec3::UnitZ();
    if (auto n = node.Find("up")) {
      up = n->Vector3();
      if (!(up.norm() > 0)) n->Fail("'up' must not be the zero vector");
    }
    const std::optional<Eigen::Isometry3d> look = LookAt(position, target, up);
    if (!look) {
      target_node.Fail(
          "cannot aim the camera: the target is the camera position, or 'up' is "
          "parallel to the viewing direction",
          "move the target, or give an 'up' that is not along the viewing direction");
    }
    return *look;
  }
  if (form == "quaternion") {
    pose.linear() = ReadQuaternion(node.Get("quaternion"));
    return pose;
  }
  const Node euler = node.Get("euler_deg");
  euler.CheckKeys({"yaw", "pitch", "roll"});
  double yaw = 0, pitch = 0, roll = 0;
  if (auto n = euler.Find("yaw")) yaw = n->Number() * kRadPerDeg;
  if (auto n = euler.Find("pitch")) pitch = n->Number() * kRadPerDeg;
  if (auto n = euler.Find("roll")) roll = n->Number() * kRadPerDeg;
  pose.linear() = RotationFromYawPitchRoll(yaw, pitch, roll);  // analysis/geometry/pose.h
  return pose;
}

Intrinsics ReadIntrinsics(const Node& node) {
  Intrinsics k;
  const Node resolution = node.Get("resolution");
  if (resolution.ArraySize("an array of 2 positive integers [width, height]") != 2) {
    resolution.Fail("expected an array of 2 positive integers [width, height], got an array of " +
                    std::to_string(resolution.value().size()));
  }
  k.width = resolution.At(0).Integer(1, kMaxResolution);
  k.height = resolution.At(1).Integer(1, kMaxResolution);

  // Lens model first: the allowed field of view depends on it.
  if (auto d = node.Find("distortion")) {
    // Typos first (against every coefficient name), then the model's own coefficients.
    d->CheckKeys({"model", "k1", "k2", "p1", "p2", "k3", "k4"});
    const Node model_node = d->Get("model");
    const std::string model = model_node.String();
    if (model == "brown_conrady") {
      k.model = LensModel::kBrownConrady;
      d->CheckKeys({"model", "k1", "k2", "p1", "p2", "k3"});
    } else if (model == "fisheye") {
      k.model = LensModel::kFisheye;
      d->CheckKeys({"model", "k1", "k2", "k3", "k4"});
    } else {
      model_node.Fail("unknown distortion model " + json(model).dump(),
                      DidYouMean(model, {"brown_conrady", "fisheye"}, "models"));
    }
    auto coefficient = [&d](const char* key, double* value) {
      if (auto n = d->Find(key)) *value = n->Number();
    };
    coefficient("k1", &k.k1);
    coefficient("k2", &k.k2);
    coefficient("p1", &k.p1);
    coefficient("p2", &k.p2);
    coefficient("k3", &k.k3);
    coefficient("k4", &k.k4);
  }

  const std::string form = node.OneOf({"hfov_deg", "focal_px", "lens"}, "focal length");
  if (form == "hfov_deg") {
    const Node n = node.Get("hfov_deg");
    const double hfov = n.Number();
    const double max = k.model == LensModel::kFisheye ? 360.0 : 180.0;
    if (!(hfov > 0 && hfov < max)) {
      n.Fail("horizontal field of view must be in (0, " + FormatNumber(max) + ") degrees for a " +
                 LensModelName(k.model) + " lens, got " + FormatNumber(hfov),
             k.model == LensModel::kFisheye
                 ? ""
                 : "for wider lenses use \"distortion\": {\"model\": \"fisheye\"}");
    }
    k.fx = k.fy = FocalFromHfov(hfov * kRadPerDeg, k.width, k.model);
  } else if (form == "focal_px") {
    const Node n = node.Get("focal_px");
    if (n.value().is_number()) {
      k.fx = k.fy = n.Positive();
    } else {
      const Vec2 f = n.Vector2();
      for (int i = 0; i < 2; ++i) {
        if (!(f[i] > 0)) n.At(i).Fail("must be positive, got " + FormatNumber(f[i]));
      }
      k.fx = f.x();
      k.fy = f.y();
    }
  } else {
    const Node lens = node.Get("lens");
    lens.CheckKeys({"focal_mm", "sensor_width_mm", "pixel_aspect"});
    k.fx = FocalFromLens(lens.Get("focal_mm").Positive(), lens.Get("sensor_width_mm").Positive(),
                         k.width);
    k.fy = k.fx;
    if (auto n = lens.Find("pixel_aspect")) k.fy = k.fx * n->Positive();
  }
  if (!std::isfinite(k.fx) || !std::isfinite(k.fy) || !(k.fx > 0) || !(k.fy > 0)) {
    node.Get(form).Fail("focal length is not a positive finite number of pixels");
  }

  k.cx = 0.5 * (k.width - 1);
  k.cy = 0.5 * (k.height - 1);
  if (auto n = node.Find("principal_point")) {
    const Vec2 c = n->Vector2();
    k.cx = c.x();
    k.cy = c.y();
  }
  return k;
}

// The pan and tilt ranges of a PTZ head ("pan_range_deg", "tilt_range_deg").
void ReadPtzRanges(const Node& node, PtzHead* head) {
  PtzHead& h = *head;
  const double el0 = h.HomeElevationDeg();
  auto range = [&](const char* key, double lo, double hi, double* out_lo, double* out_hi) {
    *out_lo = lo;
    *out_hi = hi;
    if (auto n = node.Find(key)) {
      const Vec2 r = n->Vector2();
      if (r.x() > r.y())
        n->Fail("expected [lowest, highest] degrees, got [" + FormatNumber(r.x()) + ", " +
                    FormatNumber(r.y()) + "]: the bounds are reversed",
                "write [" + FormatNumber(r.y()) + ", " + FormatNumber(r.x()) + "]");
      if (!(r.x() <= 0 && r.y() >= 0))
        n->Fail("the range must hold home (0), got [" + FormatNumber(r.x()) + ", " +
                FormatNumber(r.y()) + "]");
      if (r.x() < lo - 1e-9 || r.y() > hi + 1e-9)
        n->Fail("the range must lie within [" + FormatNumber(lo) + ", " + FormatNumber(hi) +
                    "] degrees",
                std::string(key) == "tilt_range_deg"
                    ? "the optical axis cannot tilt past straight up or down (home elevation " +
                          FormatNumber(el0) + " deg)"
                    : "a pan range spans at most one turn");
      *out_lo = r.x();
      *out_hi = r.y();
    }
  };
  range("pan_range_deg", -360, 360, &h.pan_min_deg, &h.pan_max_deg);
  if (!node.Has("pan_range_deg")) {
    h.pan_min_deg = -180;
    h.pan_max_deg = 180;
  }
  if (h.pan_max_deg - h.pan_min_deg > 360.0 + 1e-9)
    node.Get("pan_range_deg")
        .Fail("a pan range spans at most 360 degrees",
              "a head that turns without end: [-180, 180]");
  range("tilt_range_deg", -90 - el0, 90 - el0, &h.tilt_min_deg, &h.tilt_max_deg);
}

// The pan, tilt and zoom speeds and the trace time of a PTZ head.
void ReadPtzSpeeds(const Node& node, PtzHead* head) {
  PtzHead& h = *head;
  // Bounded so that every accepted head's reach and tour work is bounded (a head of 1e-12 deg/s
  // once ran analyze for minutes): the slowest 0.1 deg/s (a full turn in an hour), a trace of an
  // hour.
  auto speed = [&](const char* key, double* v, double lo, double hi, const char* unit) {
    if (auto n = node.Find(key)) {
      *v = n->Positive();
      if (!(*v >= lo && *v <= hi))
        n->Fail("expected " + std::string(unit) + " in [" + FormatNumber(lo) + ", " +
                FormatNumber(hi) + "], got " + FormatNumber(*v));
    }
  };
  speed("pan_speed_deg_s", &h.pan_speed_deg_s, 0.1, 3600, "a speed in degrees per second");
  speed("tilt_speed_deg_s", &h.tilt_speed_deg_s, 0.1, 3600, "a speed in degrees per second");
  double zoom_pct = 50;
  speed("zoom_speed_pct_s", &zoom_pct, 0.1, 10000,
        "a zoom speed in percent of the range per second");
  h.zoom_speed = zoom_pct / 100.0;
  speed("trace_s", &h.trace_s, 1e-3, 3600, "a trace time in seconds");
}

// The focal length (pixels) of a field of view node (degrees) for the lens `k`.
double PtzFocal(const Node& n, const Intrinsics& k) {
  const double hfov = n.Positive();
  const double max = k.model == LensModel::kFisheye ? 360.0 : 180.0;
  if (!(hfov < max)) n.Fail("a field of view must be below " + FormatNumber(max) + " degrees");
  return FocalFromHfov(hfov * kRadPerDeg, k.width, k.model);
}

// A PTZ setting's pan, tilt and zoom, each checked against the head's ranges.
void ReadPtzState(const Node& n, const PtzHead& h, const Intrinsics& k, PtzState* s) {
  if (auto p = n.Find("pan_deg")) {
    s->pan_deg = p->Number();
    if (s->pan_deg < h.pan_min_deg - 1e-9 || s->pan_deg > h.pan_max_deg + 1e-9)
      p->Fail("outside the pan range [" + FormatNumber(h.pan_min_deg) + ", " +
              FormatNumber(h.pan_max_deg) + "]");
  }
  if (auto p = n.Find("tilt_deg")) {
    s->tilt_deg = p->Number();
    if (s->tilt_deg < h.tilt_min_deg - 1e-9 || s->tilt_deg > h.tilt_max_deg + 1e-9)
      p->Fail("outside the tilt range [" + FormatNumber(h.tilt_min_deg) + ", " +
              FormatNumber(h.tilt_max_deg) + "]");
  }
  if (auto p = n.Find("hfov_deg")) {
    s->focal = PtzFocal(*p, k);
    if (s->focal < h.focal_min * (1 - 1e-9) || s->focal > h.focal_max * (1 + 1e-9))
      p->Fail("outside the zoom range", "zoom_hfov_deg gives the range");
    s->focal = std::clamp(s->focal, h.focal_min, h.focal_max);
  }
}

// The named presets of a PTZ head.
void ReadPtzPresets(const Node& node, const Intrinsics& k, PtzHead* head) {
  PtzHead& h = *head;
  if (auto n = node.Find("presets")) {
    const size_t count = n->ArraySize("an array of presets");
    std::set<std::string> names;
    for (size_t i = 0; i < count; ++i) {
      const Node p = n->At(i);
      p.CheckKeys({"name", "pan_deg", "tilt_deg", "hfov_deg"});
      PtzPreset preset;
      preset.name = p.Get("name").NonEmptyString();
      if (!names.insert(preset.name).second)
        p.Get("name").Fail("duplicate preset name " + Quoted(preset.name));
      preset.state.focal = h.current.focal;
      ReadPtzState(p, h, k, &preset.state);
      h.presets.push_back(preset);
    }
  }
}

// The tour of a PTZ head: stops at its presets, with dwell times.
void ReadPtzTour(const Node& node, PtzHead* head) {
  PtzHead& h = *head;
  if (auto n = node.Find("tour")) {
    const size_t count = n->ArraySize("an array of tour stops");
    if (count == 0) n->Fail("a tour needs at least one stop");
    if (count > 1000) n->Fail("a tour has at most 1000 stops, got " + std::to_string(count));
    std::vector<std::string> names;
    for (const PtzPreset& p : h.presets) names.push_back(p.name);
    for (size_t i = 0; i < count; ++i) {
      const Node stop = n->At(i);
      stop.CheckKeys({"preset", "dwell_s"});
      const Node name = stop.Get("preset");
      const std::string preset = name.NonEmptyString();
      const auto it = std::find(names.begin(), names.end(), preset);
      if (it == names.end())
        name.Fail("no preset " + Quoted(preset), DidYouMean(preset, names, "presets"));
      PtzTourStop t;
      t.preset = static_cast<int>(it - names.begin());
      t.dwell_s = stop.Get("dwell_s").NonNegative();
      if (!(t.dwell_s <= 86400))
        stop.Get("dwell_s").Fail("expected a dwell of at most a day (86400 s)");
      h.tour.push_back(t);
    }
  }
}

// A PTZ camera's head ("ptz", docs/ptz.md): its file pose is the home pose at the pivot; the
// camera becomes the head's current setting.
void ReadPtz(const Node& node, Camera* camera) {
  node.CheckKeys({"pan_deg", "tilt_deg", "hfov_deg", "pan_range_deg", "tilt_range_deg",
                  "pan_speed_deg_s", "tilt_speed_deg_s", "zoom_hfov_deg", "zoom_speed_pct_s",
                  "home_hfov_deg", "pan_axis", "offset_m", "trace_s", "presets", "tour"});
  auto head = std::make_shared<PtzHead>();
  PtzHead& h = *head;
  h.home = camera->world_from_camera;
  const Vec3 x_home = h.home.linear().col(0);
  if (auto n = node.Find("pan_axis")) {
    const Vec3 a = n->Vector3();
    if (!(a.norm() > 0)) n->Fail("the pan axis must not be the zero vector");
    h.pan_axis = a.normalized();
    if (std::abs(h.pan_axis.dot(x_home)) > 1e-6)
      n->Fail(
          "the home view's image x axis is not perpendicular to the pan axis (the head is not "
          "level)",
          "aim the camera with \"look_at\" and an \"up\" along the pan axis");
  } else {
    h.pan_axis = std::abs(x_home.z()) <= 1e-9 ? Vec3::UnitZ() : Vec3(-h.home.linear().col(1));
  }
  ReadPtzRanges(node, &h);
  ReadPtzSpeeds(node, &h);
  const Intrinsics k = camera->model.intrinsics();
  h.focal_min = h.focal_max = k.fx;
  if (auto n = node.Find("zoom_hfov_deg")) {
    if (!n->value().is_array() || n->value().size() != 2)
      n->Fail("expected [widest, narrowest] degrees");
    const double a = PtzFocal(n->At(0), k), b = PtzFocal(n->At(1), k);
    h.focal_min = std::min(a, b);
    h.focal_max = std::max(a, b);
    if (k.fx < h.focal_min * (1 - 1e-9) || k.fx > h.focal_max * (1 + 1e-9))
      n->Fail("the camera's own field of view (its current zoom) lies outside the zoom range",
              "give the camera's hfov_deg within zoom_hfov_deg");
  }
  h.home_focal = h.focal_min;
  if (auto n = node.Find("home_hfov_deg")) {
    h.home_focal = PtzFocal(*n, k);
    if (h.home_focal < h.focal_min * (1 - 1e-9) || h.home_focal > h.focal_max * (1 + 1e-9))
      n->Fail("outside the zoom range", "zoom_hfov_deg gives the range");
    h.home_focal = std::clamp(h.home_focal, h.focal_min, h.focal_max);
  }
  h.current.focal = k.fx;
  ReadPtzState(node, h, k, &h.current);
  if (node.Has("hfov_deg"))
    node.Get("hfov_deg")
        .Fail("the current zoom is the camera's own \"hfov_deg\" (or focal)",
              "remove ptz.hfov_deg");
  if (auto n = node.Find("offset_m")) {
    n->Vector3();  // three numbers
    for (int i = 0; i < 3; ++i) h.offset[i] = n->At(i).Length();
  }
  ReadPtzPresets(node, k, &h);
  ReadPtzTour(node, &h);
  *camera = h.CameraAt(*camera, h.current);
  camera->ptz = head;
}

Camera ReadCamera(const Node& node, size_t index, std::set<std::string>* ids) {
  node.CheckKeys({"id", "name", "color", "enabled", "position", "look_at", "up", "quaternion",
                  "euler_deg", "resolution", "hfov_deg", "focal_px", "lens", "principal_point",
                  "distortion", "range", "pixel_sigma", "ptz"});
  Camera camera;
  const Node id = node.Get("id");
  if (id.value().is_number_integer()) {
    camera.id = std::to_string(id.value().get<int64_t>());
  } else if (id.value().is_number()) {
    id.Number();  // Finite.
    camera.id = id.value().dump();
  } else if (id.value().is_string()) {
    camera.id = id.NonEmptyString();
  } else {
    id.Fail("expected a string or a number");
  }
  if (!ids->insert(camera.id).second) {
    id.Fail("duplicate camera id " + Quoted(camera.id), "camera ids must be unique within a rig");
  }
  camera.name = camera.id;
  if (auto n = node.Find("name")) camera.name = n->NonEmptyString();
  camera.color = CameraPaletteColor(static_cast<int>(index));
  if (auto n = node.Find("color")) camera.color = n->Color();
  if (auto n = node.Find("enabled")) camera.enabled = n->Bool();

  camera.world_from_camera = ReadPose(node);
  camera.model = CameraModel(ReadIntrinsics(node));
  if (auto n = node.Find("pixel_sigma")) camera.pixel_sigma = n->PixelSigma();

  if (auto range = node.Find("range")) {
    range->CheckKeys({"near", "far"});
    if (auto n = range->Find("near")) camera.near = n->NonNegativeLength();
    if (auto n = range->Find("far")) {
      camera.far = n->Length();
      if (!(camera.far > camera.near)) {
        n->Fail("far (" + FormatNumber(camera.far) + " m) must be greater than near (" +
                FormatNumber(camera.near) + " m)");
      }
    }
  }
  if (auto n = node.Find("ptz")) ReadPtz(*n, &camera);
  return camera;
}

Rig ReadRig(const Node& node, std::set<std::string>* names) {
  node.CheckKeys({"name", "cameras"});
  Rig rig;
  const Node name = node.Get("name");
  rig.name = name.NonEmptyString();
  if (!names->insert(rig.name).second) {
    name.Fail("duplicate rig name " + Quoted(rig.name), "rig names must be unique");
  }
  const Node cameras = node.Get("cameras");
  const size_t n = cameras.ArraySize("an array of cameras");
  if (n == 0) cameras.Fail("a rig needs at least one camera");
  if (n > size_t(SceneLimits::kMaxCameras))
    cameras.Fail(std::to_string(n) + " cameras, over the limit of " +
                     std::to_string(SceneLimits::kMaxCameras) + " per rig",
                 "split the site into several rigs (studies)");
  std::set<std::string> ids;
  for (size_t i = 0; i < n; ++i) rig.cameras.push_back(ReadCamera(cameras.At(i), i, &ids));
  return rig;
}

// "study.calibration" (docs/calibration.md): the target and how it is moved.
CalibrationSpec ReadCalibration(const Node& node) {
  node.CheckKeys({"target", "samples", "seed", "min_shared", "orientation", "board"});
  CalibrationSpec spec;
  const Node target = node.Get("target");
  const std::string kind = target.String();
  if (kind != "wand" && kind != "board")
    target.Fail(
        "expected \"wand\" or \"board\", got " + Quoted(kind),
        "a wand is one marker seen from all sides; a board is a planar checkerboard or ChArUco");
  spec.target = kind == "wand" ? CalibrationSpec::Target::kWand : CalibrationSpec::Target::kBoard;
  if (auto n = node.Find("samples")) spec.samples = n->Integer(1, 1000000);
  if (auto n = node.Find("seed")) spec.seed = static_cast<std::uint64_t>(n->Integer(0, 2147483647));
  if (auto n = node.Find("min_shared")) {
    spec.min_shared = n->Integer(1, 1000000);
    if (spec.min_shared > spec.samples)
      n->Fail("min_shared " + std::to_string(spec.min_shared) + " is more than the " +
                  std::to_string(spec.samples) + " samples: no pair of cameras could be linked",
              "lower min_shared or raise samples");
  }
  for (const char* key : {"orientation", "board"}) {
    if (spec.target == CalibrationSpec::Target::kWand && node.Has(key))
      node.Get(key).Fail(
          std::string("\"") + key + "\" applies to a board, and the target is a wand",
          "remove it, or set \"target\": \"board\"");
  }
  if (auto n = node.Find("orientation")) {
    const std::string which = n->String();
    if (which != "toward_camera" && which != "uniform")
      n->Fail("expected \"toward_camera\" or \"uniform\", got " + Quoted(which),
              "toward_camera: the board is turned to a camera that sees it; uniform: any rotation");
    spec.orientation = which == "uniform" ? CalibrationSpec::Orientation::kUniform
                                          : CalibrationSpec::Orientation::kTowardCamera;
  }
  if (auto board = node.Find("board")) {
    board->CheckKeys({"squares", "square_m", "tilt_max_deg", "min_px_per_square"});
    CalibrationBoard& b = spec.board;
    if (auto n = board->Find("squares")) {
      if (n->ArraySize("an array of 2 whole numbers of squares [x, y]") != 2)
        n->Fail("expected an array of 2 whole numbers of squares [x, y], got an array of " +
                std::to_string(n->value().size()));
      b.squares_x = n->At(0).Integer(2, 100);
      b.squares_y = n->At(1).Integer(2, 100);
    }
    if (auto n = board->Find("square_m")) b.square_m = n->PositiveLength();
    if (auto n = board->Find("tilt_max_deg")) {
      b.tilt_max_deg = n->Number();
      if (!(b.tilt_max_deg > 0 && b.tilt_max_deg < 90))
        n->Fail("must be an angle in degrees in (0, 90), got " + FormatNumber(b.tilt_max_deg),
                "detectors lose a board seen more obliquely than about 60-75 degrees");
    }
    if (auto n = board->Find("min_px_per_square")) {
      b.min_px_per_square = n->NonNegative();
      if (b.min_px_per_square > 1e5)
        n->Fail("must be at most 1e5 pixels, got " + FormatNumber(b.min_px_per_square));
    }
  }
  return spec;
}

Region ReadRegion(const Node& region, const Node& node) {
  Region out;
  region.CheckKeys({"box", "mesh"});
  const std::string kind = region.OneOf({"box", "mesh"}, "region shape");
  if (kind == "box") {
    const Node box = region.Get("box");
    box.CheckKeys({"min", "max", "center", "size"});
    out.kind = Region::Kind::kBox;
    if (box.Has("min") || box.Has("max")) {
      for (const char* key : {"center", "size"}) {
        if (box.Has(key)) {
          box.Get(key).Fail("give either 'min' and 'max' or 'center' and 'size', not both");
        }
      }
      const Vec3 min = box.Get("min").Point();
      const Node max_node = box.Get("max");
      const Vec3 max = max_node.Point();
      for (int i = 0; i < 3; ++i) {
        if (!(max[i] > min[i])) {
          max_node.At(i).Fail("max must be greater than min on every axis (axis " +
                              std::string(1, "xyz"[i]) + ")");
        }
      }
      out.box.min = min;
      out.box.max = max;
    } else {
      const Vec3 center = box.Get("center").Point();
      const Vec3 size = box.Get("size").PositiveVector3() * node.context().metres_per_unit;
      out.box.min = center - 0.5 * size;
      out.box.max = center + 0.5 * size;
    }
  } else {
    out.kind = Region::Kind::kMesh;
    const MeshReference reference = ReadMeshReference(region.Get("mesh"));
    out.file = reference.resolved;
    if (node.context().options.load_meshes) {
      TriangleMesh mesh;
      for (const MeshPart& part : LoadMeshParts(reference)) mesh.Append(part.mesh);
      mesh = WeldVertices(Transformed(mesh, reference.file_to_object));
      CheckSolid(mesh, reference.file_node, "the region mesh", "repair the mesh");
      out.box = mesh.Bounds();
      out.mesh = std::move(mesh);
    }
  }
  return out;
}

Study ReadStudy(const Node& node) {
  node.CheckKeys({"region", "voxel_size", "fields", "pixel_sigma", "memory_budget_mb", "motion",
                  "max_sigma_mm", "time", "targets", "calibration", "pixel_targets", "dori",
                  "regions", "ptz"});
  Study study;
  study.region = ReadRegion(node.Get("region"), node);
  if (auto n = node.Find("voxel_size")) study.voxel_size = n->PositiveLength();
  if (auto n = node.Find("fields")) {
    const size_t count = n->ArraySize("an array of field names");
    const std::vector<std::string>& known = FieldNames();
    if (count == 0) n->Fail("at least one field is needed", "known fields: " + JoinQuoted(known));
    study.fields.clear();
    for (size_t i = 0; i < count; ++i) study.fields.push_back(n->At(i).String());
  }
  if (auto n = node.Find("pixel_sigma")) study.pixel_sigma = n->PixelSigma();
  if (auto n = node.Find("memory_budget_mb")) {
    const double mib = n->Positive();
    CheckMemoryBudget(mib, node.context().file, n->path());
    study.memory_budget_bytes = mib * 1024.0 * 1024.0;
  }
  if (auto n = node.Find("max_sigma_mm")) study.max_sigma_mm = n->Positive();
  if (auto motion = node.Find("motion")) {
    motion->CheckKeys({"q", "rate_hz", "covariance"});
    MotionModel m;
    // q is a spectral density of acceleration, m^2/s^3: it scales with the file's length unit
    // squared.
    const double metres = node.context().metres_per_unit;
    m.q = motion->Get("q").NonNegative() * metres * metres;
    m.rate_hz = motion->Get("rate_hz").Positive();
    study.motion = m;
    if (auto c = motion->Find("covariance")) {
      const std::string which = c->String();
      if (which != "posterior" && which != "prior")
        c->Fail("expected \"posterior\" or \"prior\", got " + Quoted(which),
                "posterior is after each frame's update (the usual report), prior before it");
      study.steady_prior = which == "prior";
    }
  }
  if (auto t = node.Find("time")) {
    t->CheckKeys({"times", "poses", "samples", "min_cameras"});
    TimeStudy time;
    const int axes = int(t->Has("times")) + int(t->Has("poses")) + int(t->Has("samples"));
    if (axes > 1) t->Fail("give one of 'times', 'poses' or 'samples'");
    if (auto n = t->Find("times")) {
      const size_t count = n->ArraySize("an array of times in seconds");
      if (count == 0 || count > 100000) n->Fail("expected 1 to 100000 times");
      for (size_t i = 0; i < count; ++i) {
        const double v = n->At(i).Number();
        if (!std::isfinite(v) || std::abs(v) > 1e9)
          n->At(i).Fail("expected a time in seconds within 1e9");
        if (i > 0 && !(v > time.times.back())) n->At(i).Fail("times must increase");
        time.times.push_back(v);
      }
    }
    if (auto n = t->Find("poses")) {
      const size_t count = n->ArraySize("an array of pose names");
      if (count == 0 || count > 100000) n->Fail("expected 1 to 100000 pose names");
      for (size_t i = 0; i < count; ++i) time.poses.push_back(n->At(i).NonEmptyString());
    }
    if (auto n = t->Find("samples")) time.samples = n->Integer(1, 100000);
    if (auto n = t->Find("min_cameras")) time.min_cameras = n->Integer(1, 1000);
    study.time = time;
  }
  if (auto list = node.Find("pixel_targets")) {
    const size_t count = list->ArraySize("an array of {\"name\", \"size_m\", \"min_px\"}");
    if (count > 16) list->Fail("at most 16 pixel targets");
    std::set<std::string> names;
    for (size_t i = 0; i < count; ++i) {
      const Node t = list->At(i);
      t.CheckKeys({"name", "size_m", "min_px"});
      PixelTarget p;
      p.name = t.Get("name").NonEmptyString();
      if (!names.insert(p.name).second)
        t.Get("name").Fail("duplicate pixel target name " + Quoted(p.name));
      p.size_m = t.Get("size_m").PositiveLength();
      const Node px = t.Get("min_px");
      p.min_px = px.Positive();
      if (!(p.min_px <= 1e5)) px.Fail("expected at most 1e5 pixels");
      study.pixel_targets.push_back(p);
    }
  }
  if (auto n = node.Find("dori")) study.dori = n->Bool();
  // The PTZ fields' density target and budgets (volume/ptz_fields.h); default: the first pixel
  // target.
  if (!study.pixel_targets.empty()) {
    study.ptz.pixel_target = study.pixel_targets[0].name;
    study.ptz.min_px_per_m = study.pixel_targets[0].px_per_m();
  }
  if (auto p = node.Find("ptz")) {
    p->CheckKeys({"pixel_target", "min_px_per_m", "within_s"});
    if (p->Has("pixel_target") && p->Has("min_px_per_m"))
      p->Get("min_px_per_m").Fail("give either pixel_target or min_px_per_m, not both");
    if (auto n = p->Find("pixel_target")) {
      const std::string name = n->NonEmptyString();
      std::vector<std::string> names;
      for (const PixelTarget& t : study.pixel_targets) names.push_back(t.name);
      const auto it = std::find(names.begin(), names.end(), name);
      if (it == names.end())
        n->Fail("no pixel target " + Quoted(name), DidYouMean(name, names, "pixel_targets"));
      study.ptz.pixel_target = name;
      study.ptz.min_px_per_m = study.pixel_targets[it - names.begin()].px_per_m();
    }
    if (auto n = p->Find("min_px_per_m")) {
      study.ptz.pixel_target.clear();
      study.ptz.min_px_per_m = n->NonNegative();
      if (!(study.ptz.min_px_per_m <= 1e7)) n->Fail("expected at most 1e7 px/m");
    }
    if (auto n = p->Find("within_s")) {
      const size_t count = n->ArraySize("an array of budgets in seconds");
      if (count == 0 || count > 32) n->Fail("expected 1 to 32 budgets");
      study.ptz.within_s.clear();
      for (size_t i = 0; i < count; ++i) {
        const double t = n->At(i).Positive();
        if (!(t <= 1e6)) n->At(i).Fail("expected at most 1e6 seconds");
        study.ptz.within_s.push_back(t);
      }
    }
  }
  if (auto regions = node.Find("regions")) {
    regions->ExpectObject("an object of named regions {\"box\": ...} or {\"mesh\": ...}");
    if (regions->value().size() > 64) regions->Fail("at most 64 named regions");
    for (const auto& item : regions->value().items()) {
      const Node r(&item.value(), JsonMemberPath(regions->path(), item.key()), &node.context());
      if (item.key().empty()) r.Fail("region names must not be empty");
      study.regions.emplace_back(item.key(), ReadRegion(r, node));
    }
  }
  if (auto t = node.Find("targets")) {
    t->CheckKeys({"objects", "points", "seed"});
    SurfaceTargets targets;
    // Without "objects": every person of the scene (filled in by ParseScene).
    if (auto names = t->Find("objects")) {
      const size_t count = names->ArraySize("an array of object or group names");
      if (count == 0 || count > 1000) names->Fail("expected 1 to 1000 names");
      for (size_t i = 0; i < count; ++i) targets.names.push_back(names->At(i).NonEmptyString());
    }
    if (auto n = t->Find("points")) targets.points = n->Integer(1, 10000000);
    if (auto n = t->Find("seed")) targets.seed = std::uint64_t(n->Integer(0, 2147483647));
    study.targets = targets;
  }
  if (auto n = node.Find("calibration")) study.calibration = ReadCalibration(*n);
  // Checked after the motion model is known: steady-state fields need one.
  if (auto problem = CheckFieldList(study.fields, study.motion.has_value())) {
    const auto n = node.Find("fields");
    if (n) n->At(problem->index).Fail(problem->reason, problem->hint);
    node.Fail(problem->reason, problem->hint);  // the default list: not reachable in practice
  }
  return study;
}

View ReadView(const Node& node) {
  node.CheckKeys({"from", "at", "up", "fov_deg"});
  View view;
  view.from = node.Get("from").Point();
  const Node at = node.Get("at");
  view.at = at.Point();
  if (auto n = node.Find("up")) view.up = n->Vector3();
  if (!LookAt(view.from, view.at, view.up)) {
    at.Fail("'at' equals 'from', or 'up' is parallel to the viewing direction");
  }
  if (auto n = node.Find("fov_deg")) {
    const double fov = n->Number();
    if (!(fov > 0 && fov < 180)) n->Fail("must be in (0, 180) degrees, got " + FormatNumber(fov));
    view.fov_deg = fov;
  }
  return view;
}

// "stations": {"NAME": {"display": {"center", "facing", "up", "size", "pixels"}, "eye",
//                        "tracker": {"position", "look_at", "up", "hfov_deg", "vfov_deg",
//                        "range"}}}
ViewingStation ReadStation(const Node& node) {
  node.CheckKeys({"display", "eye", "tracker"});
  ViewingStation s;
  const Node display = node.Get("display");
  display.CheckKeys({"center", "facing", "up", "size", "pixels"});
  s.display_center = display.Get("center").Point();
  const Node facing = display.Get("facing");
  const Vec3 toward = facing.Point() - s.display_center;
  if (!(toward.norm() > 0))
    facing.Fail("'facing' (a point on the viewer's side) equals the display's center");
  s.display_normal = toward.normalized();
  if (auto n = display.Find("up")) {
    const Vec3 up = n->Vector3();
    const Vec3 in_plane = up - up.dot(s.display_normal) * s.display_normal;
    if (!(in_plane.norm() > 1e-9 * std::max(up.norm(), 1e-300)))
      n->Fail("'up' is parallel to the display's normal");
    s.display_up = in_plane.normalized();
  } else {
    const Vec3 in_plane = Vec3::UnitZ() - s.display_normal.z() * s.display_normal;
    if (!(in_plane.norm() > 1e-9))
      display.Fail("the display faces straight up or down", "give its 'up'");
    s.display_up = in_plane.normalized();
  }
  const Node size = display.Get("size");
  if (size.ArraySize("[width, height] in metres") != 2)
    size.Fail("expected [width, height] in metres");
  s.display_width = size.At(0).PositiveLength();
  s.display_height = size.At(1).PositiveLength();
  if (auto n = display.Find("pixels")) {
    if (n->ArraySize("[width, height] in pixels") != 2)
      n->Fail("expected [width, height] in pixels");
    s.pixels_wide = n->At(0).Integer(16, 8192);
    s.pixels_high = n->At(1).Integer(16, 8192);
  } else {
    s.pixels_wide = 640;
    s.pixels_high =
        std::clamp(int(std::lround(640 * s.display_height / s.display_width)), 16, 8192);
  }
  const Node eye = node.Get("eye");
  s.eye = eye.Point();
  if (!((s.eye - s.display_center).dot(s.display_normal) > 0))
    eye.Fail("the eye is behind the display or in its plane",
             "put it on the side 'facing' points to");
  if (auto t = node.Find("tracker")) {
    t->CheckKeys({"position", "look_at", "up", "hfov_deg", "vfov_deg", "range"});
    s.has_tracker = true;
    const Vec3 position = t->Get("position").Point();
    const Node look = t->Get("look_at");
    const Vec3 up = t->Find("up") ? t->Get("up").Vector3() : Vec3::UnitZ();
    const auto pose = LookAt(position, look.Point(), up);
    if (!pose) look.Fail("'look_at' equals 'position', or 'up' is parallel to the tracker's axis");
    s.tracker_pose = *pose;
    for (const char* key : {"hfov_deg", "vfov_deg"}) {
      const Node n = t->Get(key);
      const double v = n.Number();
      if (!(v > 0 && v < 180)) n.Fail("must be in (0, 180) degrees, got " + FormatNumber(v));
      (std::string(key) == "hfov_deg" ? s.tracker_hfov_deg : s.tracker_vfov_deg) = v;
    }
    const Node range = t->Get("range");
    if (range.ArraySize("[near, far] in metres") != 2) range.Fail("expected [near, far] in metres");
    s.tracker_near = range.At(0).PositiveLength();
    s.tracker_far = range.At(1).PositiveLength();
    if (!(s.tracker_near < s.tracker_far)) range.Fail("near must be less than far");
  }
  return s;
}

double ReadUnit(const Node& node) {
  const std::string unit = node.String();
  if (const double metres = MetresPerUnitNamed(unit); metres > 0) return metres;
  node.Fail("unknown unit " + json(unit).dump(), "use one of 'm', 'cm', 'mm', 'in', 'ft'");
}

}  // namespace

// -------------------------------------------------------------------------------------------------

TriangleMesh Scene::AllTriangles(std::vector<int>* triangle_object) const {
  TriangleMesh all;
  size_t vertices = 0, triangles = 0;
  for (const SceneObject& o : objects) {
    vertices += o.mesh.vertices.size();
    triangles += o.mesh.triangles.size();
  }
  all.vertices.reserve(vertices);
  all.triangles.reserve(triangles);
  if (triangle_object) {
    triangle_object->clear();
    triangle_object->reserve(triangles);
  }
  for (size_t i = 0; i < objects.size(); ++i) {
    all.Append(objects[i].mesh);
    if (triangle_object) {
      triangle_object->insert(triangle_object->end(), objects[i].mesh.triangles.size(),
                              static_cast<int>(i));
    }
  }
  return all;
}

std::vector<std::pair<std::string, std::string>> Scene::InputFiles() const {
  std::vector<std::pair<std::string, std::string>> files{{path, "scene file"}};
  const fs::path folder = fs::path(path).parent_path();
  for (const SceneObject& o : objects) {
    static const std::set<std::string> kPrimitives{"box", "sphere", "cylinder", "capsule", "plane"};
    if (o.source.empty() || kPrimitives.count(o.source)) continue;
    const fs::path p(o.source);
    files.emplace_back((p.is_absolute() ? p : folder / p).lexically_normal().string(), "mesh file");
  }
  if (!study.region.file.empty()) files.emplace_back(study.region.file, "mesh file");
  for (const auto& [name, r] : study.regions)
    if (!r.file.empty()) files.emplace_back(r.file, "mesh file");
  for (const Material& m : materials)
    if (!m.texture.empty()) files.emplace_back(m.texture, "texture");
  return files;
}

Aabb Scene::ContentBounds() const {
  Aabb bounds;
  for (const SceneObject& o : objects) bounds.Extend(o.mesh.Bounds());
  bounds.Extend(study.region.box);
  return bounds;
}

double Scene::MaxReach() const {
  const Aabb b = ContentBounds();
  if (b.empty()) return std::numeric_limits<double>::infinity();
  // A floor for degenerate content (a single flat sheet has a diagonal; a point would not).
  return SceneLimits::kReach * std::max(b.diagonal(), 1e-6);
}

void Scene::CheckReach(const Vec3& point, const std::string& option,
                       const std::string& what) const {
  const double d = (point - ContentBounds().center()).norm();
  const double reach = MaxReach();
  if (std::isfinite(reach) && !(d <= reach))
    throw InputError(option, "",
                     what + " is " + Short(d) + " m from the centre of the scene, beyond " +
                         Short(reach) + " m (" + Short(SceneLimits::kReach) +
                         " times the size of the scene's geometry and region)",
                     "check the coordinates");
}

void Scene::CheckLength(double metres, const std::string& option, const std::string& what) const {
  const double reach = MaxReach();
  if (!std::isfinite(metres) || (std::isfinite(reach) && !(std::abs(metres) <= reach)))
    throw InputError(option, "",
                     what + " " + Short(metres) + " m is beyond " + Short(reach) + " m (" +
                         Short(SceneLimits::kReach) +
                         " times the size of the scene's geometry and region)",
                     "give a length on the scale of the scene");
}

Aabb Scene::Bounds() const {
  Aabb bounds;
  for (const SceneObject& o : objects) bounds.Extend(o.mesh.Bounds());
  for (const Rig& rig : rigs) {
    for (const Camera& camera : rig.cameras) bounds.Extend(camera.center());
  }
  bounds.Extend(study.region.box);
  return bounds;
}

const Rig& Scene::FindRig(const std::string& name) const {
  if (name.empty() && !rigs.empty()) return rigs.front();
  for (const Rig& rig : rigs) {
    if (rig.name == name) return rig;
  }
  std::vector<std::string> names;
  for (const Rig& rig : rigs) names.push_back(rig.name);
  if (names.empty()) throw InputError(path, "$.rigs", "the scene has no rigs");
  throw InputError(path, "$.rigs", "no rig named " + Quoted(name),
                   DidYouMean(name, names, "rigs in this scene"));
}

// "motions": {"GROUP": {"keyframes": [{"t", "move", "yaw_deg"}, ...]} | {"poses": {"NAME": {"move",
// "yaw_deg"}}} | {"random": {"box", "yaw_deg": [lo, hi], "samples", "seed"}}}; then the study's
// time axis checked against them. The names a motion or a target may use, sorted: objects, their
// groups, and the part before the
// '/' of a mesh file's parts or of "patient/torso"-style names.
std::vector<std::string> GroupNames(const Scene& scene) {
  std::set<std::string> names;
  for (const SceneObject& o : scene.objects) {
    names.insert(o.name);
    if (!o.group.empty()) names.insert(o.group);
    const auto slash = o.name.find('/');
    if (slash != std::string::npos) names.insert(o.name.substr(0, slash));
  }
  return std::vector<std::string>(names.begin(), names.end());
}

GroupPose ReadGroupPose(const Node& node) {
  node.CheckKeys({"move", "yaw_deg", "t"});
  GroupPose p;
  if (auto n = node.Find("move")) p.move = n->Point();
  if (auto n = node.Find("yaw_deg")) {
    p.yaw_deg = n->Number();
    if (!(std::abs(p.yaw_deg) <= 36000)) n->Fail("expected degrees within 36000");
  }
  return p;
}

// The heading of a moving group as placed: a person's own, else "facing_deg" (default +x).
double GroupFacing(const Node& node, const ObjectMotion& motion, const Scene& scene) {
  if (auto n = node.Find("facing_deg")) return n->Number(-36000, 36000);
  for (const Scene::Person& p : scene.people)
    if (!p.objects.empty() && p.objects.size() == motion.objects.size() &&
        std::is_permutation(p.objects.begin(), p.objects.end(), motion.objects.begin()))
      return p.facing_deg;
  return 0;
}

// The footprints (x, y) of the solids a walker must keep clear of: solid objects that no motion
// moves, whose height overlaps the walker's [5 cm, its top].
Footprint2 StaticObstacles(const Node& motions, const ObjectMotion& walker, const Scene& scene,
                           const WanderSpec& wander) {
  Aabb body;
  for (int o : walker.objects) body.Extend(scene.objects[o].mesh.Bounds());
  const double low = body.min.z() + 0.05, high = body.max.z();
  // Only what the walker can come near: the region and its start, grown by its radius.
  Aabb reach = wander.region;
  reach.Extend(walker.anchor);
  const Vec2 lo = reach.min.head<2>() - Vec2::Constant(wander.radius),
             hi = reach.max.head<2>() + Vec2::Constant(wander.radius);
  Footprint2 out;
  for (const SceneObject& object : scene.objects) {
    if (!object.solid || object.skin >= 0) continue;
    bool moving = false;
    for (const auto& item : motions.value().items()) moving |= object.InGroup(item.key());
    if (moving) continue;
    for (const Eigen::Vector3i& t : object.mesh.triangles) {
      const Vec3 &a = object.mesh.vertices[t[0]], &b = object.mesh.vertices[t[1]],
                 &c = object.mesh.vertices[t[2]];
      if (std::max({a.z(), b.z(), c.z()}) < low || std::min({a.z(), b.z(), c.z()}) > high) continue;
      if (std::max({a.x(), b.x(), c.x()}) < lo.x() || std::min({a.x(), b.x(), c.x()}) > hi.x() ||
          std::max({a.y(), b.y(), c.y()}) < lo.y() || std::min({a.y(), b.y(), c.y()}) > hi.y())
        continue;
      out.triangles.push_back({a.head<2>(), b.head<2>(), c.head<2>()});
    }
  }
  return out;
}

// "walk": {"path": [[x, y], ...], "speed", "start_s", "turn_s", "closed", "facing_deg"} or
// "wander": {"region": {"min": [x, y], "max": [x, y]}, "duration_s", "speed", "pause_s",
// "turn_s", "radius", "seed", "facing_deg"}: keyframes (analysis/scene/builders.h).
std::vector<std::pair<double, GroupPose>> ReadWalk(const Node& node, const std::string& kind,
                                                   const ObjectMotion& motion, const Node& motions,
                                                   const Scene& scene) {
  const double facing = GroupFacing(node, motion, scene);
  auto speed = [&node](double fallback) {
    if (auto n = node.Find("speed")) {
      const double v = n->PositiveLength();
      if (v < 0.01 || v > 100) n->Fail("expected a speed of 0.01 to 100 m/s");
      return v;
    }
    return fallback;
  };
  if (kind == "walk") {
    node.CheckKeys({"path", "speed", "start_s", "turn_s", "closed", "facing_deg"});
    WalkSpec walk;
    walk.path = ReadPolygon(node.Get("path"), 100000);
    if (walk.path.size() < 2) node.Get("path").Fail("a walk needs at least 2 way points");
    for (std::size_t i = 1; i < walk.path.size(); ++i)
      if ((walk.path[i] - walk.path[i - 1]).norm() < 1e-3)
        node.Get("path").At(i).Fail("the same way point twice in a row");
    walk.speed = speed(walk.speed);
    if (auto n = node.Find("start_s")) walk.start_s = n->Number(-1e6, 1e6);
    if (auto n = node.Find("turn_s")) walk.turn_s = n->Number(0, 60);
    if (auto n = node.Find("closed")) walk.closed = n->Bool();
    return WalkKeyframes(walk, motion.anchor, facing);
  }
  node.CheckKeys(
      {"region", "duration_s", "speed", "pause_s", "turn_s", "radius", "seed", "facing_deg"});
  WanderSpec wander;
  const Node region = node.Get("region");
  region.CheckKeys({"min", "max"});
  const Vec2 lo = region.Get("min").Vector2() * node.context().metres_per_unit,
             hi = region.Get("max").Vector2() * node.context().metres_per_unit;
  for (int i = 0; i < 2; ++i)
    if (!(hi[i] > lo[i]))
      region.Get("max").At(i).Fail("max must be greater than min (axis " + std::string(1, "xy"[i]) +
                                   ")");
  wander.region.Extend(Vec3(lo.x(), lo.y(), 0));
  wander.region.Extend(Vec3(hi.x(), hi.y(), 0));
  if (auto n = node.Find("duration_s")) wander.duration_s = n->Number(0.1, 86400);
  wander.speed = speed(wander.speed);
  if (auto n = node.Find("pause_s")) wander.pause_s = n->Number(0, 3600);
  if (auto n = node.Find("turn_s")) wander.turn_s = n->Number(0, 60);
  if (auto n = node.Find("radius")) wander.radius = n->PositiveLength();
  if (auto n = node.Find("seed")) wander.seed = std::uint64_t(n->Integer(0, 2147483647));
  std::vector<OtherWalker> others;
  for (const ObjectMotion& m : scene.motions)
    if (m.kind == ObjectMotion::Kind::kKeyframes) others.push_back({m.anchor, m.keyframes});
  try {
    return WanderKeyframes(wander, motion.anchor, facing,
                           StaticObstacles(motions, motion, scene, wander), others);
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what(), "place the group where it is free, or give a smaller \"radius\"");
  }
  return {};
}

void ReadMotions(const Node& motions, Scene* scene) {
  motions.ExpectObject("an object of motions by group or object name");
  std::vector<int> owner(scene->objects.size(), -1);
  for (const auto& item : motions.value().items()) {
    const Node m(&item.value(), JsonMemberPath(motions.path(), item.key()), &motions.context());
    ObjectMotion motion;
    motion.name = item.key();
    Aabb bounds;
    for (std::size_t o = 0; o < scene->objects.size(); ++o) {
      const SceneObject& object = scene->objects[o];
      if (!object.InGroup(motion.name)) continue;
      if (owner[o] >= 0)
        m.Fail("object " + Quoted(object.name) + " is moved by motion " +
                   Quoted(scene->motions[owner[o]].name) + " already",
               "an object belongs to one moving group");
      owner[o] = int(scene->motions.size());
      motion.objects.push_back(int(o));
      bounds.Extend(object.mesh.Bounds());
    }
    if (motion.objects.empty())
      m.Fail("no object or group named " + Quoted(motion.name),
             DidYouMean(motion.name, GroupNames(*scene), "objects and groups"));
    if (!bounds.empty())
      motion.anchor = Vec3(bounds.center().x(), bounds.center().y(), bounds.min.z());
    m.CheckKeys({"keyframes", "poses", "random", "walk", "wander"});
    const std::string kind =
        m.OneOf({"keyframes", "poses", "random", "walk", "wander"}, "kind of motion");
    if (kind == "walk" || kind == "wander") {
      motion.kind = ObjectMotion::Kind::kKeyframes;
      motion.keyframes = ReadWalk(m.Get(kind), kind, motion, motions, *scene);
    } else if (kind == "keyframes") {
      motion.kind = ObjectMotion::Kind::kKeyframes;
      const Node k = m.Get("keyframes");
      const size_t count = k.ArraySize("an array of keyframes {\"t\", \"move\", \"yaw_deg\"}");
      if (count == 0 || count > 100000) k.Fail("expected 1 to 100000 keyframes");
      for (size_t i = 0; i < count; ++i) {
        const Node f = k.At(i);
        const double t = f.Get("t").Number();
        if (!std::isfinite(t) || std::abs(t) > 1e9)
          f.Get("t").Fail("expected a time in seconds within 1e9");
        if (i > 0 && !(t > motion.keyframes.back().first))
          f.Get("t").Fail("keyframe times must increase");
        motion.keyframes.emplace_back(t, ReadGroupPose(f));
      }
    } else if (kind == "poses") {
      motion.kind = ObjectMotion::Kind::kPoses;
      const Node p = m.Get("poses");
      p.ExpectObject("an object of named poses {\"move\", \"yaw_deg\"}");
      if (p.value().empty()) p.Fail("at least one pose is needed");
      for (const auto& pose : p.value().items()) {
        const Node n(&pose.value(), JsonMemberPath(p.path(), pose.key()), &motions.context());
        if (pose.key().empty()) n.Fail("pose names must not be empty");
        if (n.Has("t"))
          n.Get("t").Fail("a named pose has no time", "use \"keyframes\" for timed poses");
        motion.poses.emplace_back(pose.key(), ReadGroupPose(n));
      }
    } else {
      motion.kind = ObjectMotion::Kind::kRandom;
      const Node r = m.Get("random");
      r.CheckKeys({"box", "yaw_deg", "samples", "seed"});
      const Node box = r.Get("box");
      box.CheckKeys({"min", "max"});
      motion.box.min = box.Get("min").Point();
      motion.box.max = box.Get("max").Point();
      for (int i = 0; i < 3; ++i)
        if (!(motion.box.max[i] >= motion.box.min[i]))
          box.Get("max").At(i).Fail("max must not be less than min (axis " +
                                    std::string(1, "xyz"[i]) + ")");
      if (auto y = r.Find("yaw_deg")) {
        const Vec2 range = y->Vector2();
        if (!(range[0] <= range[1]) ||
            !(std::abs(range[0]) <= 36000 && std::abs(range[1]) <= 36000))
          y->Fail("expected [min, max] degrees with min <= max, within 36000");
        motion.yaw_min_deg = range[0];
        motion.yaw_max_deg = range[1];
      }
      if (auto n = r.Find("samples")) motion.samples = n->Integer(1, 100000);
      if (auto n = r.Find("seed")) motion.seed = std::uint64_t(n->Integer(0, 2147483647));
    }
    scene->motions.push_back(std::move(motion));
  }
}

// The study's time axis against the motions: every motion must be evaluable at every sample.
void CheckTimeAxis(const Node& root, const Scene& scene) {
  const std::optional<TimeStudy>& time = scene.study.time;
  const auto time_node = root.Get("study").Find("time");
  if (scene.motions.empty()) {
    if (time_node && scene.skins.empty())
      time_node->Fail(
          "the study has a time axis but the scene has no \"motions\" and no \"animation\"",
          "remove it, or add motions or an animated mesh");
    if (time && !time->poses.empty())
      time_node->Get("poses").Fail(
          "the study's time axis names poses but no motion has named poses",
          "give \"times\" or \"samples\" for animated meshes");
    return;
  }
  bool any_keyframes = false;
  const ObjectMotion* first_poses = nullptr;
  for (const ObjectMotion& m : scene.motions) {
    any_keyframes |= m.kind == ObjectMotion::Kind::kKeyframes;
    if (m.kind == ObjectMotion::Kind::kPoses && !first_poses) first_poses = &m;
  }
  const Node motions = root.Get("motions");
  std::vector<std::string> names;
  if (time && !time->poses.empty())
    names = time->poses;
  else if (!(time && (!time->times.empty() || time->samples > 0)) && first_poses)
    for (const auto& [name, pose] : first_poses->poses) names.push_back(name);
  const bool by_pose = !names.empty();
  for (const ObjectMotion& m : scene.motions) {
    const Node node = motions.Get(m.name);
    if (m.kind == ObjectMotion::Kind::kKeyframes && by_pose)
      node.Fail(
          "a keyframed motion cannot be evaluated at named poses",
          "give the study's \"time\" as \"times\" or \"samples\", or give this group named poses");
    if (m.kind == ObjectMotion::Kind::kPoses) {
      if (!by_pose)
        (time_node ? *time_node : node)
            .Fail("motion " + Quoted(m.name) +
                      " has named poses but the study's time axis is not a list of poses",
                  "give \"time\": {\"poses\": [...]} in the study");
      for (const std::string& name : names) {
        bool found = false;
        for (const auto& [pose, value] : m.poses) found |= pose == name;
        if (!found) {
          std::vector<std::string> have;
          for (const auto& [pose, value] : m.poses) have.push_back(pose);
          node.Get("poses").Fail(
              "no pose " + Quoted(name) + " (asked for by the study's time axis)",
              DidYouMean(name, have, "poses of this group"));
        }
      }
    }
  }
  (void)any_keyframes;
}

Scene ParseScene(const std::string& json_text, const std::string& path,
                 const LoadOptions& options) {
  Context context;
  context.file = path;
  context.folder = fs::path(path).parent_path();
  context.options = options;
  const json root_value = ParseJson(json_text, path);
  const Node root(&root_value, "$", &context);
  root.CheckKeys({"pandora", "units", "materials", "objects", "rigs", "study", "views", "stations",
                  "motions"});

  Scene scene;
  scene.path = path;
  scene.sha256 = Sha256Hex(json_text);

  if (auto n = root.Find("pandora")) {
    if (!n->value().is_number() || n->Number() != 1) {
      n->Fail("unsupported format version " + n->value().dump(), "this build reads version 1");
    }
  }
  if (auto n = root.Find("units")) context.metres_per_unit = ReadUnit(*n);

  std::map<std::string, int> material_index;
  if (auto materials = root.Find("materials")) {
    materials->ExpectObject("an object of named materials");
    for (const auto& item : materials->value().items()) {
      const Node m(&item.value(), JsonMemberPath(materials->path(), item.key()), &context);
      if (item.key().empty()) m.Fail("material names must not be empty");
      material_index[item.key()] = AddMaterial(&scene, ReadMaterial(m, item.key()));
    }
  }

  if (auto objects = root.Find("objects")) {
    const size_t n = objects->ArraySize("an array of objects");
    std::set<std::string> names;
    // The study's memory budget bounds each mesh import too, unless a command's option set one
    // (read before the study itself, which comes after the objects; checked there).
    std::optional<ScopedMeshImportBudget> import_budget;
    if (!ScopedMeshImportBudget::active() && root_value.is_object() &&
        root_value.contains("study") && root_value["study"].is_object() &&
        root_value["study"].contains("memory_budget_mb")) {
      const json& mb = root_value["study"]["memory_budget_mb"];
      if (mb.is_number() && mb.get<double>() > 0 && std::isfinite(mb.get<double>()))
        import_budget.emplace(mb.get<double>() * 1048576.0, "$.study.memory_budget_mb of " + path);
    }
    for (size_t i = 0; i < n; ++i) ReadObject(objects->At(i), material_index, &names, &scene);
  }

  const Node rigs = root.Get("rigs");
  const size_t rig_count = rigs.ArraySize("an array of rigs");
  if (rig_count == 0) rigs.Fail("at least one rig is needed");
  std::set<std::string> rig_names;
  for (size_t i = 0; i < rig_count; ++i) scene.rigs.push_back(ReadRig(rigs.At(i), &rig_names));

  scene.study = ReadStudy(root.Get("study"));

  if (auto motions = root.Find("motions")) ReadMotions(*motions, &scene);
  if (scene.study.targets && scene.study.targets->names.empty()) {
    if (scene.people.empty())
      root.Get("study").Get("targets").Fail(
          "no \"objects\" are given and the scene has no people",
          "list the objects or groups whose surfaces are targets");
    for (const Scene::Person& p : scene.people) scene.study.targets->names.push_back(p.name);
  } else if (scene.study.targets) {
    const Node names = root.Get("study").Get("targets").Get("objects");
    const std::vector<std::string> known = GroupNames(scene);
    for (size_t i = 0; i < scene.study.targets->names.size(); ++i) {
      const std::string& name = scene.study.targets->names[i];
      if (!std::binary_search(known.begin(), known.end(), name))
        names.At(i).Fail("no object or group named " + Quoted(name),
                         DidYouMean(name, known, "objects and groups"));
    }
  }
  if (root.Has("motions") || scene.study.time) CheckTimeAxis(root, scene);

  if (auto views = root.Find("views")) {
    views->ExpectObject("an object of named views");
    for (const auto& item : views->value().items()) {
      const Node v(&item.value(), JsonMemberPath(views->path(), item.key()), &context);
      if (item.key().empty()) v.Fail("view names must not be empty");
      scene.views[item.key()] = ReadView(v);
    }
  }
  if (auto stations = root.Find("stations")) {
    stations->ExpectObject("an object of named viewing stations");
    for (const auto& item : stations->value().items()) {
      const Node v(&item.value(), JsonMemberPath(stations->path(), item.key()), &context);
      if (item.key().empty()) v.Fail("station names must not be empty");
      scene.stations[item.key()] = ReadStation(v);
    }
  }

  // Cameras and viewpoints within reach of the scene: beyond it, single-precision ray casting has
  // no digits left for the scene (docs/robustness.md).
  const double reach = scene.MaxReach();
  const Vec3 centre = scene.ContentBounds().center();
  auto check_reach = [&](const Node& node, const Vec3& p, const std::string& what) {
    const double d = (p - centre).norm();
    if (std::isfinite(reach) && !(d <= reach))
      node.Fail(what + " is " + Short(d) + " m from the centre of the scene, beyond " +
                    Short(reach) + " m (" + Short(SceneLimits::kReach) +
                    " times the size of the scene's geometry and region)",
                "check the coordinates and the file's \"units\"");
  };
  for (size_t r = 0; r < scene.rigs.size(); ++r)
    for (size_t c = 0; c < scene.rigs[r].cameras.size(); ++c)
      check_reach(rigs.At(r).Get("cameras").At(c).Get("position"),
                  scene.rigs[r].cameras[c].center(), "the camera");
  if (auto views = root.Find("views"))
    for (const auto& [name, view] : scene.views)
      check_reach(views->Get(name).Get("from"), view.from, "the viewpoint");
  if (auto stations = root.Find("stations"))
    for (const auto& [name, station] : scene.stations) {
      check_reach(stations->Get(name).Get("eye"), station.eye, "the station's eye");
      check_reach(stations->Get(name).Get("display").Get("center"), station.display_center,
                  "the display");
    }
  return scene;
}

void CheckMemoryBudget(double mib, const std::string& file, const std::string& json_path) {
  const double physical_mib = static_cast<double>(PhysicalMemoryBytes()) / 1048576.0;
  if (physical_mib > 0 && !(mib <= physical_mib)) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "a budget of %.4g MiB is more than this machine's memory (%.0f MiB)", mib,
                  physical_mib);
    throw InputError(file, json_path, text,
                     "give at most the memory this machine has, in MiB; the default is 4096");
  }
}

const std::vector<std::string>& FieldNames() {
  static const std::vector<std::string> names{
      "coverage",  "cameras",          "resolution",
      "sigma_max", "sigma_mean",       "triangulation_angle",
      "condition", "sigma_max_steady", "sigma_mean_steady"};
  return names;
}

bool IsUncertaintyField(const std::string& name) {
  const std::vector<std::string>& all = FieldNames();
  return std::find(all.begin() + 3, all.end(), name) != all.end();
}

std::optional<FieldListProblem> CheckFieldList(const std::vector<std::string>& fields,
                                               bool has_motion) {
  const std::vector<std::string>& known = FieldNames();
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string& name = fields[i];
    if (std::find(known.begin(), known.end(), name) == known.end())
      return FieldListProblem{i, "unknown field " + Quoted(name),
                              DidYouMean(name, known, "known fields")};
    if (std::find(fields.begin(), fields.begin() + i, name) != fields.begin() + i)
      return FieldListProblem{i, "field " + Quoted(name) + " is listed twice", ""};
    if (!has_motion && name.size() > 7 && name.compare(name.size() - 7, 7, "_steady") == 0)
      return FieldListProblem{i, "field " + Quoted(name) + " needs a motion model",
                              "add \"motion\": {\"q\": ..., \"rate_hz\": ...} to the study"};
  }
  return std::nullopt;
}

Scene LoadScene(const std::string& path, const LoadOptions& options) {
  return ParseScene(ReadInputFile(path, InputLimits::kJsonBytes, "scene file"), path, options);
}

json RigToJson(const Rig& rig) {
  json cameras = json::array();
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    const Eigen::Quaterniond q(camera.world_from_camera.rotation());
    const Vec3 p = camera.center();
    json c = {
        {"id", camera.id},
        {"name", camera.name},
        {"color", {camera.color.x(), camera.color.y(), camera.color.z()}},
        {"enabled", camera.enabled},
        {"position", {p.x(), p.y(), p.z()}},
        {"quaternion", {q.w(), q.x(), q.y(), q.z()}},
        {"resolution", {k.width, k.height}},
        {"focal_px", {k.fx, k.fy}},
        {"principal_point", {k.cx, k.cy}},
    };
    if (k.model == LensModel::kBrownConrady) {
      c["distortion"] = {{"model", "brown_conrady"},
                         {"k1", k.k1},
                         {"k2", k.k2},
                         {"p1", k.p1},
                         {"p2", k.p2},
                         {"k3", k.k3}};
    } else if (k.model == LensModel::kFisheye) {
      c["distortion"] = {
          {"model", "fisheye"}, {"k1", k.k1}, {"k2", k.k2}, {"k3", k.k3}, {"k4", k.k4}};
    }
    json range = {{"near", camera.near}};
    if (std::isfinite(camera.far)) range["far"] = camera.far;
    c["range"] = range;
    if (camera.pixel_sigma > 0) c["pixel_sigma"] = camera.pixel_sigma;
    if (camera.ptz) {
      // The file pose of a PTZ camera is its home at the pivot; the lens is the current zoom.
      const PtzHead& h = *camera.ptz;
      const Eigen::Quaterniond qh(h.home.rotation());
      const Vec3 pivot = h.home.translation();
      c["position"] = {pivot.x(), pivot.y(), pivot.z()};
      c["quaternion"] = {qh.w(), qh.x(), qh.y(), qh.z()};
      const auto hfov = [&](double f) { return HfovFromFocal(f, k.width, k.model) / kRadPerDeg; };
      json ptz = {{"pan_deg", h.current.pan_deg},
                  {"tilt_deg", h.current.tilt_deg},
                  {"pan_axis", {h.pan_axis.x(), h.pan_axis.y(), h.pan_axis.z()}},
                  {"pan_range_deg", {h.pan_min_deg, h.pan_max_deg}},
                  {"tilt_range_deg", {h.tilt_min_deg, h.tilt_max_deg}},
                  {"pan_speed_deg_s", h.pan_speed_deg_s},
                  {"tilt_speed_deg_s", h.tilt_speed_deg_s},
                  {"zoom_speed_pct_s", h.zoom_speed * 100.0},
                  {"offset_m", {h.offset.x(), h.offset.y(), h.offset.z()}},
                  {"trace_s", h.trace_s}};
      if (h.focal_max > h.focal_min) {
        ptz["zoom_hfov_deg"] = {hfov(h.focal_min), hfov(h.focal_max)};
        ptz["home_hfov_deg"] = hfov(h.home_focal);
      }
      json presets = json::array();
      for (const PtzPreset& p : h.presets)
        presets.push_back({{"name", p.name},
                           {"pan_deg", p.state.pan_deg},
                           {"tilt_deg", p.state.tilt_deg},
                           {"hfov_deg", hfov(p.state.focal)}});
      if (!h.presets.empty()) ptz["presets"] = std::move(presets);
      json tour = json::array();
      for (const PtzTourStop& s : h.tour)
        tour.push_back({{"preset", h.presets[s.preset].name}, {"dwell_s", s.dwell_s}});
      if (!h.tour.empty()) ptz["tour"] = std::move(tour);
      c["ptz"] = std::move(ptz);
    }
    cameras.push_back(std::move(c));
  }
  return json{{"name", rig.name}, {"cameras", std::move(cameras)}};
}

Rig ParseRigJson(const json& rig, const std::string& path, const std::string& json_path) {
  Context context;
  context.file = path;
  context.folder = fs::path(path).parent_path();
  std::set<std::string> names;
  return ReadRig(Node(&rig, json_path, &context), &names);
}

}  // namespace pandora
