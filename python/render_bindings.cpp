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
#include "analysis/util/text.h"
#include "app/session/study.h"
#include "python/bindings.h"
#include "render/light.h"
#include "render/render.h"

namespace pandora::python {

// render(): the projective-light render as a numpy array.
void BindRender(py::module_& m) {
  m.def(
      "render",
      [](const PyScene& s, const PyRig& r, const std::string& view, int width, int height,
         const std::string& plan, const std::string& pattern, const std::string& surface,
         const std::optional<double>& brightness, int grid_pixels, int samples) {
        const Scene& scene = s.scene();
        RenderView v;
        RenderOptions o;
        const std::optional<Pattern> p = PatternFromName(pattern);
        if (!p)
          throw InputError("pattern", "", "unknown pattern '" + pattern + "'",
                           DidYouMean(pattern, PatternNames(), "patterns"));
        const std::optional<Surface> f = SurfaceFromName(surface);
        if (!f)
          throw InputError("surface", "", "unknown surface mode '" + surface + "'",
                           DidYouMean(surface, SurfaceNames(), "surface modes"));
        o.pattern = *p;
        o.surface = *f;
        if (brightness) o.brightness = *brightness;
        o.grid_pixels = grid_pixels;
        o.samples = samples;
        o.Check();  // before the view: the options' own errors name their keyword
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
      py::arg("height") = 400, py::arg("plan") = "", py::arg("pattern") = "uniform",
      py::arg("surface") = "material", py::arg("brightness") = py::none(),
      py::arg("grid_pixels") = 32, py::arg("samples") = 1,
      "The projective-light render as an (H, W, 3) float32 linear RGB array, as `pandora render` "
      "draws it: pattern uniform or grid (a line every grid_pixels camera pixels), surface "
      "material, black, hidden-line or contours, brightness (default min(1, 3 / enabled "
      "cameras)), samples per pixel per axis.");
}

}  // namespace pandora::python
