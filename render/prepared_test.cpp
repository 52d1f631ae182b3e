// The prepared renderer and progressive rendering: a PreparedScene over a given ray caster traces
// every ray through that caster and renders what the one-shot Render renders, bit for bit, for
// every surface mode, pattern, sampling, view kind and overlay; the last progressive pass equals
// Render bit for bit, each earlier pass shows its traced pixels exactly and the nearest traced
// pixel elsewhere; cancelled passes keep the previous image and resume without tracing a pixel
// twice; progress is the share of pixels traced.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

#include "analysis/geometry/primitives.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "render/prepared_scene.h"
#include "render/progressive.h"
#include "render/render.h"
#include "tests/fixtures.h"
#include "volume/fields.h"

namespace pandora {
namespace {

Camera Cam(const std::string& id, const Vec3& from, const Vec3& at, double hfov_deg,
           const Vec3& color, LensModel lens = LensModel::kPinhole, double k1 = 0, double k2 = 0) {
  Camera c = testing::WithIntrinsics(
      testing::TestCamera(id, from, at, hfov_deg, 64, 48, lens, Vec3(0, 0, 1)), [&](Intrinsics& k) {
        k.k1 = k1;
        k.k2 = k2;
      });
  c.color = color;
  return c;
}

// A floor, a ball and a box lit by three cameras (Brown-Conrady, pinhole, fisheye), with a study
// region for fields (overlays).
struct World {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  World() {
    scene.path = "prepared_test.json";
    SceneObject floor;
    floor.name = "floor";
    floor.mesh = MakePlane(Vec2(20, 20));
    scene.objects.push_back(floor);
    SceneObject ball;
    ball.name = "ball";
    ball.mesh = MakeSphere(0.35, 24);
    for (Vec3& v : ball.mesh.vertices) v += Vec3(0.2, -0.1, 0.6);
    scene.objects.push_back(ball);
    SceneObject box;
    box.name = "box";
    box.mesh = MakeBox(Vec3(0.5, 0.3, 0.8));
    for (Vec3& v : box.mesh.vertices) v += Vec3(-0.6, 0.4, 0.4);
    scene.objects.push_back(box);
    Rig rig;
    rig.name = "three";
    rig.cameras.push_back(Cam("a", Vec3(1.5, -1.5, 2), Vec3(0, 0, 0.3), 60, Vec3(1, 0, 0),
                              LensModel::kBrownConrady, -0.1, 0.01));
    rig.cameras.push_back(Cam("b", Vec3(-1.5, -1.2, 1.8), Vec3(0, 0, 0.3), 70, Vec3(0, 1, 0)));
    rig.cameras.push_back(Cam("c", Vec3(0.2, 1.8, 2.2), Vec3(0, 0, 0.3), 80, Vec3(0, 0, 1),
                              LensModel::kFisheye, 0.01));
    scene.rigs.push_back(rig);
    scene.study.region.kind = Region::Kind::kBox;
    scene.study.region.box.min = Vec3(-1, -1, 0.05);
    scene.study.region.box.max = Vec3(1, 1, 1.25);
    scene.study.voxel_size = 0.1;
    caster = MakeEmbreeRayCaster(scene.AllTriangles());
  }
  const Rig& rig() const { return scene.rigs[0]; }
};

// An odd size, so the right and bottom tiles are partial and some blocks are cut.
RenderView MainView() {
  RenderView v;
  v.from = Vec3(0.5, -3.0, 2.5);
  v.at = Vec3(0, 0, 0.4);
  v.fov_deg = 55;
  v.width = 77;
  v.height = 53;
  return v;
}

// The option sets every comparison runs over.
struct Variant {
  const char* name;
  RenderOptions options;
  bool camera_view = false;
};
std::vector<Variant> Variants() {
  std::vector<Variant> v;
  RenderOptions o;  // material surfaces, uniform light, wireframes, key, layers
  v.push_back({"material", o});
  o.pattern = Pattern::kGrid;
  o.grid_pixels = 8;
  o.surface = Surface::kHiddenLine;
  o.line_width_px = 1.5;
  v.push_back({"grid_hidden_line", o});
  o = RenderOptions();
  o.surface = Surface::kContours;
  v.push_back({"contours", o});
  o = RenderOptions();
  o.surface = Surface::kBlack;
  o.samples = 3;
  o.brightness = 0.5;
  v.push_back({"black_3x3_samples", o});
  o = RenderOptions();
  o.pattern = Pattern::kGrid;
  o.grid_pixels = 8;
  o.samples = 2;
  v.push_back({"camera_view_grid_2x2_samples", o, true});
  return v;
}

RenderView ViewOf(const Variant& v) {
  if (!v.camera_view) return MainView();
  RenderView c;
  c.camera = 0;
  c.width = 61;
  c.height = 45;
  return c;
}

// Bit-for-bit equality of every buffer.
template <class T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
void ExpectSameImage(const Image& a, const Image& b, const std::string& what) {
  ASSERT_EQ(a.width, b.width) << what;
  ASSERT_EQ(a.height, b.height) << what;
  EXPECT_TRUE(SameBits(a.rgb, b.rgb)) << what << ": rgb";
  EXPECT_TRUE(SameBits(a.coverage, b.coverage)) << what << ": coverage";
  EXPECT_TRUE(SameBits(a.cameras, b.cameras)) << what << ": cameras";
  EXPECT_TRUE(SameBits(a.resolution, b.resolution)) << what << ": resolution";
  EXPECT_TRUE(SameBits(a.sigma_max, b.sigma_max)) << what << ": sigma_max";
  EXPECT_TRUE(SameBits(a.depth, b.depth)) << what << ": depth";
  EXPECT_TRUE(SameBits(a.object, b.object)) << what << ": object";
}

// A caster that delegates to another and counts the rays traced through it.
class CountingCaster final : public RayCaster {
 public:
  explicit CountingCaster(const RayCaster& inner) : inner_(inner) {}
  bool Occluded(const Ray& ray) const override {
    ++occluded_;
    return inner_.Occluded(ray);
  }
  std::optional<RayHit> Intersect(const Ray& ray) const override {
    ++intersected_;
    return inner_.Intersect(ray);
  }
  void OccludedPacket(const Ray* rays, std::size_t count, uint8_t* occluded) const override {
    occluded_ += count;
    inner_.OccludedPacket(rays, count, occluded);
  }
  void IntersectPacket(const Ray* rays, std::size_t count,
                       std::optional<RayHit>* hits) const override {
    intersected_ += count;
    inner_.IntersectPacket(rays, count, hits);
  }
  const char* name() const override { return "counting"; }
  const Aabb& bounds() const override { return inner_.bounds(); }
  std::size_t triangle_count() const override { return inner_.triangle_count(); }
  std::size_t intersected() const { return intersected_; }
  std::size_t occluded() const { return occluded_; }
  void Reset() { intersected_ = occluded_ = 0; }

 private:
  const RayCaster& inner_;
  mutable std::atomic<std::size_t> intersected_{0}, occluded_{0};
};

TEST(PreparedScene, RendersTheOneShotImageBitForBitThroughTheGivenCaster) {
  const World w;
  CountingCaster counting(*w.caster);
  const PreparedScene prepared(w.scene, counting);
  EXPECT_EQ(&prepared.caster(), &counting);  // no BVH of its own
  EXPECT_EQ(prepared.triangle_count(), w.caster->triangle_count());
  EXPECT_EQ(counting.intersected() + counting.occluded(), 0u);  // preparing traces nothing
  for (const Variant& v : Variants()) {
    SCOPED_TRACE(v.name);
    const RenderView view = ViewOf(v);
    const Image once = Render(w.scene, w.rig(), *w.caster, view, v.options);
    counting.Reset();
    RenderStats stats;
    const Image frame = RenderWithStats(prepared, w.rig(), view, v.options, nullptr, &stats);
    ExpectSameImage(frame, once, v.name);
    // Every ray of the frame went through the caster it was given.
    EXPECT_EQ(counting.intersected(), stats.primary_rays);
    EXPECT_EQ(counting.occluded(), stats.shadow_rays);
    EXPECT_GT(stats.shadow_rays, 1000u);
  }
}

TEST(PreparedScene, FieldOverlaysPreparedOnceMatchTheOneShotOverlays) {
  const World w;
  FieldOptions fo;
  fo.fields = {"coverage", "resolution"};
  const Fields fields = EvaluateFields(w.scene, w.rig(), *w.caster, fo);
  RenderOptions options;
  options.overlays.slice_field = "coverage";
  options.overlays.slice_axis = 2;
  options.overlays.slice_position = 0.45;
  options.overlays.iso_field = "coverage";
  options.overlays.iso_value = 1.5;
  const PreparedScene prepared(w.scene, *w.caster);
  const PreparedOverlays overlays(fields, options.overlays);
  EXPECT_TRUE(overlays.Matches(options.overlays));
  const RenderView view = MainView();
  ExpectSameImage(Render(prepared, w.rig(), view, options, &overlays),
                  Render(w.scene, w.rig(), *w.caster, view, options, &fields),
                  "slice and isosurface");
  // What a frame may still vary (the slice's range, opacities) needs no new preparation.
  options.overlays.slice_min = 0;
  options.overlays.slice_max = 3;
  options.overlays.iso_opacity = 0.8;
  EXPECT_TRUE(overlays.Matches(options.overlays));
  ExpectSameImage(Render(prepared, w.rig(), view, options, &overlays),
                  Render(w.scene, w.rig(), *w.caster, view, options, &fields),
                  "range and opacity changed");
  // Another plane or iso value does.
  RenderOptions moved = options;
  moved.overlays.slice_position = 0.55;
  EXPECT_FALSE(overlays.Matches(moved.overlays));
  EXPECT_THROW(Render(prepared, w.rig(), view, moved, &overlays), std::invalid_argument);
  moved = options;
  moved.overlays.iso_value = 2.5;
  EXPECT_FALSE(overlays.Matches(moved.overlays));
  // A slice at NaN (the middle of the fields) matches a NaN.
  RenderOptions middle;
  middle.overlays.slice_field = "resolution";
  const PreparedOverlays at_middle(fields, middle.overlays);
  EXPECT_TRUE(at_middle.Matches(middle.overlays));
  // Overlays asked for but none given: the command line's error.
  try {
    Render(prepared, w.rig(), view, options, nullptr);
    ADD_FAILURE() << "no error without overlays";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "{fields}");
  }
  // A grid the fields lack: named at preparation.
  RenderOptions missing;
  missing.overlays.slice_field = "sigma_max";
  try {
    PreparedOverlays bad(fields, missing.overlays);
    ADD_FAILURE() << "no error for a missing grid";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "{slice_field}");
  }
}

TEST(PreparedScene, OnePreparationServesEditedRigsAndMovedViews) {
  const World w;
  const PreparedScene prepared(w.scene, *w.caster);
  Rig rig = w.rig();
  RenderView view = MainView();
  RenderOptions options;
  options.layers = true;
  for (int edit = 0; edit < 4; ++edit) {
    if (edit == 1)
      rig.cameras[1].world_from_camera =
          *LookAt(Vec3(-1.2, -1.6, 1.5), Vec3(0.1, 0, 0.2), Vec3(0, 0, 1));
    if (edit == 2) rig.cameras[2].enabled = false;
    if (edit == 3) {
      rig.cameras[0].color = Vec3(1, 1, 0);
      view.from = Vec3(-2.0, -2.5, 1.5);
      view.width = 40;
      view.height = 70;
    }
    ExpectSameImage(Render(prepared, rig, view, options),
                    Render(w.scene, rig, *w.caster, view, options), "edit " + std::to_string(edit));
  }
}

TEST(PreparedScene, ConcurrentFramesShareTheLazyPreparation) {
  const World w;
  const RenderView view = MainView();
  RenderOptions hidden;
  hidden.surface = Surface::kHiddenLine;  // prepares the edge table at first use
  const RenderOptions material;           // prepares the textures at first use
  const Image expected_hidden = Render(w.scene, w.rig(), *w.caster, view, hidden);
  const Image expected_material = Render(w.scene, w.rig(), *w.caster, view, material);
  for (int round = 0; round < 3; ++round) {
    const PreparedScene prepared(w.scene, *w.caster);
    Image a, b, c, d;
    std::thread t1([&] { a = Render(prepared, w.rig(), view, hidden); });
    std::thread t2([&] { b = Render(prepared, w.rig(), view, hidden); });
    std::thread t3([&] { c = Render(prepared, w.rig(), view, material); });
    d = Render(prepared, w.rig(), view, material);
    t1.join();
    t2.join();
    t3.join();
    ExpectSameImage(a, expected_hidden, "thread 1");
    ExpectSameImage(b, expected_hidden, "thread 2");
    ExpectSameImage(c, expected_material, "thread 3");
    ExpectSameImage(d, expected_material, "main thread");
  }
}

TEST(PreparedScene, OwnsOrSharesItsCasterAndRefusesAForeignOne) {
  const World w;
  // Shared ownership: the caster lives as long as the prepared scene.
  std::shared_ptr<const RayCaster> shared = MakeEmbreeRayCaster(w.scene.AllTriangles());
  const RayCaster* raw = shared.get();
  const PreparedScene prepared(w.scene, shared);
  const Image expected = Render(w.scene, w.rig(), *raw, MainView(), RenderOptions());
  shared.reset();
  EXPECT_EQ(&prepared.caster(), raw);
  ExpectSameImage(Render(prepared, w.rig(), MainView(), RenderOptions()), expected,
                  "shared caster");
  // Its own BVH, from the scene's triangles.
  const PreparedScene own(w.scene);
  EXPECT_EQ(own.triangle_count(), w.caster->triangle_count());
  EXPECT_EQ(own.caster().triangle_count(), w.caster->triangle_count());
  // No caster, or one of other triangles.
  EXPECT_THROW(PreparedScene(w.scene, std::shared_ptr<const RayCaster>()), std::invalid_argument);
  const auto other = MakeEmbreeRayCaster(MakeBox(Vec3(1, 1, 1)));
  EXPECT_THROW(PreparedScene(w.scene, *other), std::invalid_argument);
  // The view is checked per frame, with the command line's option names.
  RenderView bad = MainView();
  bad.fov_deg = 180;
  try {
    Render(prepared, w.rig(), bad, RenderOptions());
    ADD_FAILURE() << "no error for fov 180";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "{fov_deg}");
  }
}

TEST(Progressive, LastPassEqualsRenderBitForBit) {
  const World w;
  const PreparedScene prepared(w.scene, *w.caster);
  for (const Variant& v : Variants()) {
    SCOPED_TRACE(v.name);
    const RenderView view = ViewOf(v);
    ProgressiveRender progressive(prepared, w.rig(), view, v.options);
    EXPECT_EQ(progressive.passes_done(), 0);
    EXPECT_EQ(progressive.image().width, 0);
    std::vector<int> passes;
    EXPECT_TRUE(progressive.RunAll({}, [&](const Image& image, int pass) {
      passes.push_back(pass);
      EXPECT_EQ(image.width, view.width);
    }));
    EXPECT_EQ(passes, (std::vector<int>{0, 1, 2, 3}));
    EXPECT_TRUE(progressive.done());
    EXPECT_TRUE(progressive.RunPass());  // nothing left to do
    ExpectSameImage(progressive.image(), Render(prepared, w.rig(), view, v.options), v.name);
  }
}

// Pass p traces the pixels whose x and y are multiples of b = 8 >> p; every pixel then shows the
// traced pixel at (min(round(x / b) b, last), ...) with the values the final image has there.
TEST(Progressive, EachPassShowsItsTracedPixelsAndTheNearestTracedPixelElsewhere) {
  const World w;
  const PreparedScene prepared(w.scene, *w.caster);
  RenderOptions options;  // no image-space overlays: the previews' pixels are the traced ones
  options.pattern = Pattern::kGrid;
  options.grid_pixels = 8;
  options.surface = Surface::kBlack;
  options.overlays.cameras = false;
  options.overlays.key = false;
  const RenderView view = MainView();
  const Image final_image = Render(prepared, w.rig(), view, options);
  ProgressiveRender progressive(prepared, w.rig(), view, options);
  const int W = view.width, H = view.height;
  for (int pass = 0; pass < ProgressiveRender::kPasses; ++pass) {
    ASSERT_TRUE(progressive.RunPass());
    const Image& img = progressive.image();
    const int b = ProgressiveRender::BlockSize(pass);
    EXPECT_EQ(b, 8 >> pass);
    int mismatches = 0, copies = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const int sx = std::min(int(std::floor(double(x) / b + 0.5)) * b, (W - 1) / b * b);
        const int sy = std::min(int(std::floor(double(y) / b + 0.5)) * b, (H - 1) / b * b);
        const std::size_t p = std::size_t(y) * W + x, q = std::size_t(sy) * W + sx;
        copies += p != q;
        mismatches += img.rgb[3 * p] != final_image.rgb[3 * q] ||
                      img.rgb[3 * p + 1] != final_image.rgb[3 * q + 1] ||
                      img.rgb[3 * p + 2] != final_image.rgb[3 * q + 2] ||
                      img.coverage[p] != final_image.coverage[q] ||
                      img.cameras[p] != final_image.cameras[q] ||
                      img.depth[p] != final_image.depth[q] ||
                      img.object[p] != final_image.object[q] ||
                      img.resolution[p] != final_image.resolution[q] ||
                      img.sigma_max[p] != final_image.sigma_max[q];
      }
    EXPECT_EQ(mismatches, 0) << "pass " << pass;
    // Traced: ceil(W / b) * ceil(H / b) pixels; the rest are copies.
    EXPECT_EQ(copies, W * H - ((W + b - 1) / b) * ((H + b - 1) / b)) << "pass " << pass;
  }
}

// Serial (one thread), so where the cancellation lands is deterministic.
TEST(Progressive, CancelledPassKeepsThePreviousImageResumesAndTracesEveryPixelOnce) {
  const World w;
  CountingCaster counting(*w.caster);
  const PreparedScene prepared(w.scene, counting);
  const RenderView view = MainView();
  const RenderOptions options;
  RenderStats stats;
  const Image expected = RenderWithStats(prepared, w.rig(), view, options, nullptr, &stats);
  counting.Reset();
  tbb::task_arena serial(1);
  serial.execute([&] {
    ProgressiveRender progressive(prepared, w.rig(), view, options);
    std::atomic<bool> cancel{true};
    std::vector<double> reported;
    RenderControl control;
    control.cancel = &cancel;
    control.progress = [&](double f) { reported.push_back(f); };
    // Cancelled before it starts: nothing traced, no image.
    EXPECT_FALSE(progressive.RunPass(control));
    EXPECT_EQ(progressive.passes_done(), 0);
    EXPECT_EQ(counting.intersected(), 0u);
    EXPECT_TRUE(reported.empty());
    cancel = false;
    ASSERT_TRUE(progressive.RunPass(control));
    // Pass 0 traced ceil(77 / 8) * ceil(53 / 8) = 70 of the 4081 pixels, and says so at its end.
    ASSERT_FALSE(reported.empty());
    EXPECT_EQ(reported.back(), 70.0 / 4081.0);
    const Image after_pass0 = progressive.image();
    // Pass 1, cancelled from the progress report once a percent of the frame is traced.
    control.progress = [&](double f) {
      reported.push_back(f);
      if (f >= 70.0 / 4081.0 + 0.01) cancel = true;
    };
    EXPECT_FALSE(progressive.RunPass(control));
    EXPECT_EQ(progressive.passes_done(), 1);
    ExpectSameImage(progressive.image(), after_pass0, "image after the cancelled pass");
    const double at_cancel = reported.back();
    EXPECT_GT(at_cancel, 70.0 / 4081.0);
    EXPECT_LT(at_cancel, 280.0 / 4081.0);  // pass 1 ends at ceil(77/4) ceil(53/4) = 280 pixels
    // Resumed: the remaining passes complete; the last equals Render.
    cancel = false;
    control.progress = [&](double f) { reported.push_back(f); };
    EXPECT_TRUE(progressive.RunAll(control));
    EXPECT_EQ(reported.back(), 1.0);
    for (std::size_t i = 1; i < reported.size(); ++i) EXPECT_GE(reported[i], reported[i - 1]) << i;
    ExpectSameImage(progressive.image(), expected, "after the resumed passes");
  });
  // Every primary ray once over the whole run, cancellation included, and the same shadow rays.
  EXPECT_EQ(counting.intersected(), stats.primary_rays);
  EXPECT_EQ(counting.occluded(), stats.shadow_rays);
}

TEST(Progressive, RestartRendersTheNextFrameAsANewRenderWould) {
  const World w;
  const PreparedScene prepared(w.scene, *w.caster);
  const RenderOptions options;
  ProgressiveRender progressive(prepared, w.rig(), MainView(), options);
  ASSERT_TRUE(progressive.RunPass());
  // A camera moves while the frame is being refined: start over with the edited rig.
  Rig moved = w.rig();
  moved.cameras[0].world_from_camera =
      *LookAt(Vec3(1.0, -1.8, 2.2), Vec3(0.2, 0, 0.3), Vec3(0, 0, 1));
  progressive.Restart(moved, MainView(), options);
  EXPECT_EQ(progressive.passes_done(), 0);
  EXPECT_EQ(progressive.image().width, 0);
  ASSERT_TRUE(progressive.RunAll());
  ExpectSameImage(progressive.image(), Render(prepared, moved, MainView(), options),
                  "moved camera");
  // Then the eye moves and the size changes; and back to the first size with contours.
  RenderView other = MainView();
  other.from = Vec3(-1.5, -2.5, 1.2);
  other.width = 100;
  other.height = 31;
  progressive.Restart(moved, other, options);
  ASSERT_TRUE(progressive.RunAll());
  ExpectSameImage(progressive.image(), Render(prepared, moved, other, options),
                  "moved eye, new size");
  RenderOptions contours;
  contours.surface = Surface::kContours;
  progressive.Restart(w.rig(), MainView(), contours);
  ASSERT_TRUE(progressive.RunAll());
  ExpectSameImage(progressive.image(), Render(prepared, w.rig(), MainView(), contours), "contours");
  // A bad view throws and leaves the frame as it was.
  RenderView bad = MainView();
  bad.width = 0;
  EXPECT_THROW(progressive.Restart(w.rig(), bad, options), InputError);
  EXPECT_TRUE(progressive.done());
  ExpectSameImage(progressive.image(), Render(prepared, w.rig(), MainView(), contours),
                  "after a refused restart");
}

}  // namespace
}  // namespace pandora
