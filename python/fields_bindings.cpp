// `import pandora`, fields (docs/python.md): evaluate() (what `pandora analyze` computes),
// pandora.Fields (sparse and dense arrays, write() as fields.vdb), and visibility() and
// covariance() at given points.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/session/analyze.h"
#include "app/session/study.h"
#include "python/bindings.h"
#include "volume/fields.h"
#include "volume/fields_vdb.h"
#include "volume/ptz_fields.h"
#include "volume/summary.h"
#include "volume/vdb_io.h"

namespace pandora::python {
namespace {

std::string VoxelText(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.12g", v);
  return b;
}

openvdb::FloatGrid::ConstPtr FloatGrid(const PyFields& f, const std::string& name) {
  const Fields::Impl& g = f.fields->impl();
  if (auto grid = g.Float(name)) return grid;
  if (auto it = g.extra.find(name); it != g.extra.end()) return it->second;
  return nullptr;
}

double SigmaOf(const Scene& scene, const Camera& c) {
  return c.pixel_sigma > 0 ? c.pixel_sigma : scene.study.pixel_sigma;
}

}  // namespace

// pandora.Fields: evaluated grids as sparse or dense arrays, and write().
void BindFields(py::module_& m) {
  py::class_<PyFields>(m, "Fields",
                       "Evaluated fields over the study region (sparse OpenVDB grids).")
      .def_property_readonly("names", [](const PyFields& f) { return f.names; })
      .def_property_readonly(
          "summary",
          [](const PyFields& f) {
            return py::module_::import("json").attr("loads")(f.summary.dump());
          },
          "summary.json of this evaluation, as a dict.")
      .def(
          "sparse",
          [](const PyFields& f, const std::string& name) {
            // Active voxels: (ijk (N, 3) int32, centres (N, 3) metres, values (N,)).
            const Fields::Impl& g = f.fields->impl();
            std::vector<openvdb::Coord> ijk;
            std::vector<double> values;
            if (name == "coverage" && g.coverage) {
              ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int v) {
                ijk.push_back(c);
                values.push_back(v);
              });
            } else if (auto grid = FloatGrid(f, name)) {
              ForEachActiveVoxel(*grid, [&](const openvdb::Coord& c, float v) {
                ijk.push_back(c);
                values.push_back(v);
              });
            } else {
              throw InputError("sparse", "", "no field '" + name + "' was evaluated");
            }
            const std::size_t n = ijk.size();
            py::array_t<int> idx({n, std::size_t(3)});
            py::array_t<double> xyz({n, std::size_t(3)});
            py::array_t<double> val(n);
            auto I = idx.mutable_unchecked<2>();
            auto X = xyz.mutable_unchecked<2>();
            auto V = val.mutable_unchecked<1>();
            for (std::size_t i = 0; i < n; ++i) {
              const openvdb::Vec3d w = g.transform->indexToWorld(ijk[i]);
              for (int a = 0; a < 3; ++a) {
                I(i, a) = ijk[i][a];
                X(i, a) = w[a];
              }
              V(i) = values[i];
            }
            return py::make_tuple(idx, xyz, val);
          },
          py::arg("name"))
      .def(
          "dense",
          [](const PyFields& f, const std::string& name) {
            // The whole lattice (nx, ny, nz), NaN where the field has no value (unseen, solid,
            // outside).
            const VoxelLattice& L = f.fields->lattice;
            py::array_t<double> out(
                {std::size_t(L.dims.x()), std::size_t(L.dims.y()), std::size_t(L.dims.z())});
            auto O = out.mutable_unchecked<3>();
            for (py::ssize_t i = 0; i < O.shape(0); ++i)
              for (py::ssize_t j = 0; j < O.shape(1); ++j)
                for (py::ssize_t k = 0; k < O.shape(2); ++k) O(i, j, k) = kNaN;
            const Fields::Impl& g = f.fields->impl();
            auto put = [&](const openvdb::Coord& c, double v) {
              const openvdb::Coord& o = c;  // index (0, 0, 0) is the lattice's origin
              if (o.x() >= 0 && o.y() >= 0 && o.z() >= 0 && o.x() < L.dims.x() &&
                  o.y() < L.dims.y() && o.z() < L.dims.z())
                O(o.x(), o.y(), o.z()) = v;
            };
            if (name == "coverage" && g.coverage)
              ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int v) { put(c, v); });
            else if (auto grid = FloatGrid(f, name))
              ForEachActiveVoxel(*grid, [&](const openvdb::Coord& c, float v) { put(c, v); });
            else
              throw InputError("dense", "", "no field '" + name + "' was evaluated");
            return out;
          },
          py::arg("name"))
      .def(
          "write",
          [](const PyFields& f, const std::string& path) {
            const Scene& scene = f.study->scene();
            RefuseInputPath(scene, path, "fields.vdb");
            const std::map<std::string, std::string> meta{
                {"units", "m"},
                {"tool", "pandora (python)"},
                {"scene_file", scene.path},
                {"scene_sha256", scene.sha256},
                {"rig_name", f.rig_name},
                {"rig", f.rig_json},
                {"voxel_size_m", VoxelText(scene.study.voxel_size)}};
            py::gil_scoped_release release;
            WriteFieldsVdb(*f.fields, path, meta);
          },
          py::arg("path"),
          "Writes the grids as `pandora analyze` writes fields.vdb (atomically; never over an "
          "input).");
}

// evaluate(): the fields for a rig.
void BindEvaluate(py::module_& m) {
  m.def(
      "evaluate",
      [](const PyScene& s, const PyRig& r, std::vector<std::string> fields) {
        const Scene& scene = s.scene();
        const Rig rig = r.rig();  // a copy: the evaluation runs without the GIL
        // What `pandora analyze` computes (app/session/analyze.h): the fields, then the time
        // samples, surface targets, pixel targets, DORI, warnings, calibration, N-1 and PTZ.
        session::AnalyzeOptions analysis;
        FieldOptions& o = analysis.fields;
        o.fields = fields.empty() ? scene.study.fields : fields;
        if (!fields.empty()) o.fields_option = "{fields}";
        o.scene_path = scene.path;
        o.memory_budget_bytes = scene.study.memory_budget_bytes;
        // A script names the fields it wants: pixel targets and DORI where those fields hold what
        // they need (analyze, which evaluates the study's fields or --fields, refuses instead).
        auto has = [&o](const char* f) {
          return std::find(o.fields.begin(), o.fields.end(), f) != o.fields.end();
        };
        if (!fields.empty()) {
          analysis.pixel_targets = has("coverage") && has("cameras");
          analysis.dori = has("coverage") && has("resolution");
        }
        PyFields out;
        out.study = s.study;
        session::RigAnalysis result;
        {
          py::gil_scoped_release release;
          session::RigFieldsAnalysis a = session::AnalyzeRig(*s.study, rig, analysis);
          out.fields = std::make_shared<Fields>(std::move(a.fields));
          result = std::move(a.analysis);
        }
        out.names = o.fields;
        for (const auto& [name, grid] : out.fields->impl().extra) out.names.push_back(name);
        out.summary = result.summary;
        out.rig_name = rig.name;
        out.rig_json = RigToJson(rig).dump();
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("fields") = std::vector<std::string>{},
      "Evaluates the fields (default: the study's) for the rig's enabled cameras, and what "
      "`pandora analyze` computes beside them (time samples, surface targets, pixel targets, DORI, "
      "warnings, calibration, N-1, PTZ reach and tours): the same summary and the same grids.");
}

// visibility() and covariance() at given points.
void BindPointQueries(py::module_& m) {
  m.def(
      "visibility",
      [](const PyScene& s, const PyRig& r,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
        const std::vector<Vec3> X = Points(points);
        const VisibilityTester tester(r.rig().cameras, s.study->caster(),
                                      s.scene().ContentBounds().diagonal());
        const std::size_t C = r.rig().cameras.size();
        py::array_t<bool> out({X.size(), C});
        auto O = out.mutable_unchecked<2>();
        for (std::size_t i = 0; i < X.size(); ++i)
          for (std::size_t c = 0; c < C; ++c)
            O(i, c) = r.rig().cameras[c].enabled && tester.Test(int(c), X[i]) == ViewResult::kSeen;
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("points"),
      "(N, C) booleans: camera c sees point i (image, range, occlusion; the field evaluation's "
      "rules).");

  m.def(
      "covariance",
      [](const PyScene& s, const PyRig& r,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
        const Scene& scene = s.scene();
        const std::vector<Vec3> X = Points(points);
        const VisibilityTester tester(r.rig().cameras, s.study->caster(),
                                      scene.ContentBounds().diagonal());
        py::array_t<double> out({X.size(), std::size_t(3), std::size_t(3)});
        auto O = out.mutable_unchecked<3>();
        for (std::size_t i = 0; i < X.size(); ++i) {
          Mat3 J = Mat3::Zero();
          int cameras = 0;
          for (std::size_t c = 0; c < r.rig().cameras.size(); ++c) {
            if (!r.rig().cameras[c].enabled) continue;
            Mat23 A;
            if (tester.Test(int(c), X[i], nullptr, &A) != ViewResult::kSeen) continue;
            const double sigma = SigmaOf(scene, r.rig().cameras[c]);
            J += A.transpose() * A / (sigma * sigma);
            ++cameras;
          }
          const StaticUncertainty u = StaticFromInformation(DecomposeInformation(J), cameras);
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) O(i, a, b) = u.triangulable ? u.covariance(a, b) : kNaN;
        }
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("points"),
      "(N, 3, 3) triangulation covariance (m^2) from the cameras that see each point; NaN where "
      "not triangulable.");
}

}  // namespace pandora::python
