// The camera catalogue of `pandora propose` (docs/propose.md "Catalogue").
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "analysis/util/error.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/units.h"
#include "suggest/propose.h"

namespace pandora {
namespace {

// A number or a [min, max] range; `zooms` settings spread over a range (its ends included).
std::vector<double> Settings(const JsonNode& node, double lo, double hi, int zooms) {
  if (node.value().is_number()) return {node.Number(lo, hi)};
  const Eigen::VectorXd r = node.Numbers(2);
  for (int i = 0; i < 2; ++i)
    if (!(r[i] >= lo && r[i] <= hi))
      node.At(std::size_t(i)).Fail("expected " + std::to_string(lo) + " to " + std::to_string(hi));
  if (!(r[1] >= r[0])) node.Fail("expected [min, max] with min <= max");
  std::vector<double> out;
  for (int z = 0; z < zooms; ++z)
    out.push_back(zooms == 1 ? r[0] : r[0] + (r[1] - r[0]) * z / (zooms - 1));
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

std::vector<ProposeLens> ReadCameraCatalogue(const std::string& path, int zooms) {
  const nlohmann::json document = ReadJsonFile(path, "camera catalogue");
  const JsonNode root = JsonNode::Root(document, path);
  root.CheckKeys({"models"});
  const JsonNode models = root.Get("models");
  const std::size_t n = models.ArraySize(1000, "an array of camera models");
  if (n == 0) models.Fail("at least one camera model is needed");
  std::vector<ProposeLens> out;
  std::set<std::string> names;
  for (std::size_t i = 0; i < n; ++i) {
    const JsonNode m = models.At(i);
    m.CheckKeys({"name", "resolution", "hfov_deg", "focal_mm", "sensor_width_mm", "distortion",
                 "price", "range"});
    ProposeLens lens;
    lens.model = m.Get("name").NonEmptyString();
    if (!names.insert(lens.model).second) m.Get("name").Fail("duplicate model name");
    const Eigen::VectorXd res = m.Get("resolution").Numbers(2);
    for (int k = 0; k < 2; ++k)
      if (!(res[k] >= 16 && res[k] <= 65536 && res[k] == std::floor(res[k])))
        m.Get("resolution")
            .At(std::size_t(k))
            .Fail("expected a whole number of pixels, 16 to 65536");
    Intrinsics in;
    in.width = int(res[0]), in.height = int(res[1]);
    in.cx = 0.5 * (in.width - 1), in.cy = 0.5 * (in.height - 1);
    if (auto d = m.Find("distortion")) {
      d->CheckKeys({"model", "k1", "k2", "p1", "p2", "k3", "k4"});
      const std::string model = d->Get("model").Enum({"brown_conrady", "fisheye"});
      in.model = model == "fisheye" ? LensModel::kFisheye : LensModel::kBrownConrady;
      double* coefficient[6] = {&in.k1, &in.k2, &in.p1, &in.p2, &in.k3, &in.k4};
      const char* key[6] = {"k1", "k2", "p1", "p2", "k3", "k4"};
      for (int c = 0; c < 6; ++c)
        if (auto v = d->Find(key[c])) *coefficient[c] = v->Number(-10, 10);
    }
    if (auto p = m.Find("price")) lens.price = p->Number(0, 1e9);
    if (auto r = m.Find("range")) {
      r->CheckKeys({"near", "far"});
      if (auto v = r->Find("near")) lens.near = v->Number(0, 1e6);
      if (auto v = r->Find("far")) lens.far = v->Number(0, 1e9);
      if (!(lens.far > lens.near)) r->Fail("far must be greater than near");
    }
    std::vector<double> hfovs;
    if (m.Has("hfov_deg") == (m.Has("focal_mm") || m.Has("sensor_width_mm")))
      m.Fail("give \"hfov_deg\", or \"focal_mm\" with \"sensor_width_mm\"");
    if (auto h = m.Find("hfov_deg")) {
      hfovs = Settings(*h, 1, in.model == LensModel::kFisheye ? 360 : 179, zooms);
    } else {
      const double sensor = m.Get("sensor_width_mm").Number(0.1, 100);
      for (double f : Settings(m.Get("focal_mm"), 0.1, 2000, zooms))
        hfovs.push_back(HfovFromFocal(FocalFromLens(f, sensor, in.width), in.width, in.model) *
                        kDegPerRad);
    }
    for (double hfov : hfovs) {
      ProposeLens at = lens;
      at.hfov_deg = hfov;
      at.intrinsics = in;
      at.intrinsics.fx = at.intrinsics.fy = FocalFromHfov(hfov * kRadPerDeg, in.width, in.model);
      out.push_back(at);
    }
  }
  return out;
}

}  // namespace pandora
