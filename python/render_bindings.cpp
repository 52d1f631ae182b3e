// `import pandora`, render (docs/python.md): the projective-light render of a scene view or a plan
// / elevation as a numpy array.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <optional>
#include <string>

#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/session/study.h"
#include "python/bindings.h"
#include "render/render.h"

namespace pandora::python {

// render(): the projective-light render as a numpy array.
void BindRender(py::module_& m) {
  m.def(
      "render",
      [](const PyScene& s, const PyRig& r, const std::string& view, int width, int height,
         const std::string& plan) {
        const Scene& scene = s.scene();
        RenderView v;
        RenderOptions o;
        if (!plan.empty()) {
          double mpp = 0;
          const std::optional<RenderView> p =
              PlanView(scene.ContentBounds(), plan, width, height,
                       plan == "plan" ? scene.study.region.box.max.z() : kNaN, &mpp);
          if (!p)
            throw InputError("plan", "", "unknown side '" + plan + "'",
                             "use plan, north, south, east or west");
          v = *p;
          o.overlays.labels = true;
        } else {
          auto it = scene.views.find(view);
          if (view.empty() && !scene.views.empty()) it = scene.views.begin();
          if (it == scene.views.end())
            throw InputError("view", "", "no view '" + view + "' in the scene");
          v = ViewFromScene(it->second, width, height);
        }
        o.pixel_sigma = scene.study.pixel_sigma;
        Image image;
        {
          py::gil_scoped_release release;
          image = Render(scene, r.rig(), s.study->caster(), v, o);
        }
        py::array_t<float> out(
            {std::size_t(image.height), std::size_t(image.width), std::size_t(3)});
        std::copy(image.rgb.begin(), image.rgb.end(), out.mutable_data());
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("view") = "", py::arg("width") = 640,
      py::arg("height") = 400, py::arg("plan") = "",
      "The projective-light render as an (H, W, 3) float32 linear RGB array.");
}

}  // namespace pandora::python
