// The DXF side of plan_import.h: the only file that includes dxflib.
#include <dl_creationadapter.h>
#include <dl_dxf.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "analysis/scene/plan_import.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"

namespace pandora {
namespace {

// $INSUNITS codes (AutoCAD's): metres per unit; 0 (unitless) and codes without a length are not
// listed.
const std::map<int, std::pair<double, const char*>>& InsUnits() {
  static const std::map<int, std::pair<double, const char*>> kUnits = {
      {1, {0.0254, "in"}},  {2, {0.3048, "ft"}},         {3, {1609.344, "mi"}},
      {4, {0.001, "mm"}},   {5, {0.01, "cm"}},           {6, {1.0, "m"}},
      {7, {1000.0, "km"}},  {8, {2.54e-8, "microinch"}}, {9, {2.54e-5, "mil"}},
      {10, {0.9144, "yd"}}, {13, {1e-6, "micron"}},      {14, {0.1, "dm"}}};
  return kUnits;
}

class PlanReader : public DL_CreationAdapter {
 public:
  void setVariableInt(const std::string& key, int value, int code) override {
    if (key == "$INSUNITS") insunits = value;
  }
  void addLine(const DL_LineData& d) override {
    Finish();
    PlanDrawing::Polyline p;
    p.layer = attributes.getLayer();
    p.points = {Vec2(d.x1, d.y1), Vec2(d.x2, d.y2)};
    drawing.polylines.push_back(std::move(p));
  }
  void addPolyline(const DL_PolylineData& d) override {
    Finish();
    current.emplace();
    current->layer = attributes.getLayer();
    current->closed = (d.flags & 1) != 0;
  }
  void addVertex(const DL_VertexData& d) override {
    if (current) current->points.emplace_back(d.x, d.y);
  }
  void endSequence() override { Finish(); }
  void addArc(const DL_ArcData&) override { Skip(); }
  void addCircle(const DL_CircleData&) override { Skip(); }
  void addInsert(const DL_InsertData&) override { Skip(); }
  void addText(const DL_TextData&) override { Skip(); }
  void addMText(const DL_MTextData&) override { Skip(); }
  void addEllipse(const DL_EllipseData&) override { Skip(); }
  void addSpline(const DL_SplineData&) override { Skip(); }
  void addPoint(const DL_PointData&) override { Skip(); }
  void addBlock(const DL_BlockData&) override {
    Finish();
    ++in_block;
  }
  void endBlock() override {
    Finish();
    in_block = std::max(0, in_block - 1);
  }

  void Finish() {
    if (current && in_block == 0 && current->points.size() >= 2)
      drawing.polylines.push_back(std::move(*current));
    current.reset();
  }
  void Skip() {
    Finish();
    ++drawing.skipped;
  }

  PlanDrawing drawing;
  std::optional<PlanDrawing::Polyline> current;
  int insunits = -1, in_block = 0;
};

}  // namespace

PlanDrawing ReadDxfPlan(const std::string& path, std::optional<double> units) {
  // Within the input limits (a size cap; InputError otherwise), then parsed from memory.
  constexpr std::uint64_t kMaxPlanBytes = 512ull << 20;
  const std::string text = ReadInputFile(path, kMaxPlanBytes, "floor plan");
  std::istringstream stream(text);
  PlanReader reader;
  DL_Dxf dxf;
  bool ok = false;
  try {
    ok = dxf.in(stream, &reader);
  } catch (const std::exception& e) {
    throw InputError(path, "", std::string("the DXF file cannot be parsed: ") + e.what());
  }
  reader.Finish();
  if (!ok) throw InputError(path, "", "the DXF file cannot be parsed");
  PlanDrawing drawing = std::move(reader.drawing);
  if (drawing.polylines.empty() && drawing.skipped == 0)
    throw InputError(path, "",
                     "the file holds no DXF entities (not a DXF drawing, or an empty one)",
                     "export the floor plan from CAD as DXF (ASCII or binary)");
  // Lines inside block definitions are parts of blocks (door symbols, furniture), not the plan.
  if (units) {
    drawing.metres_per_unit = *units;
    drawing.units = "as given on the command line";
  } else {
    const auto it = InsUnits().find(reader.insunits);
    if (it == InsUnits().end())
      throw InputError(path, "",
                       reader.insunits < 0
                           ? "the drawing does not say its unit (no $INSUNITS in its header)"
                           : "the drawing's unit ($INSUNITS " + std::to_string(reader.insunits) +
                                 ") is not a length",
                       "give {units} m|cm|mm|in|ft");
    drawing.metres_per_unit = it->second.first;
    drawing.units = "$INSUNITS " + std::to_string(it->first) + " (" + it->second.second + ")";
  }
  std::set<std::string> layers;
  for (PlanDrawing::Polyline& p : drawing.polylines) {
    for (Vec2& v : p.points) {
      v *= drawing.metres_per_unit;
      if (!(std::abs(v.x()) <= 1e6 && std::abs(v.y()) <= 1e6))
        throw InputError(path, "",
                         "a point on layer '" + p.layer + "' is not finite or beyond 1e6 m",
                         "check the drawing's unit");
    }
    layers.insert(p.layer);
  }
  drawing.layers.assign(layers.begin(), layers.end());
  return drawing;
}

}  // namespace pandora
