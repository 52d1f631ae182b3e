// Progressive rendering (render/progressive.h): the groups of frame.h run level by level over all
// tiles, each completed level shown at full size with the missing pixels taken from the nearest
// traced one.
#include "render/progressive.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <mutex>

#include "render/frame.h"
#include "render/prepared_scene.h"

namespace pandora {

struct ProgressiveRender::State {
  explicit State(const PreparedScene& scene) : scene(scene) {}

  // A new frame; the buffers keep their memory when the size is unchanged. Throws before changing
  // anything.
  void Start(const Rig& new_rig, const RenderView& view, const RenderOptions& options,
             const PreparedOverlays* overlays) {
    auto r = std::make_unique<const Rig>(new_rig);
    auto f = std::make_unique<const internal::FrameRenderer>(scene, *r, view, options, overlays);
    frame = std::move(f);  // before the rig it refers to is replaced
    rig = std::move(r);
    frame->Reset(&base);
    done.assign(std::size_t(frame->tiles()) * internal::kLevels, 0);
    passes = 0;
    traced = 0;
    total = std::int64_t(frame->width()) * frame->height();
    reported = 0;
    shown.image.width = shown.image.height = 0;  // no pass yet (the buffers stay allocated)
  }

  const PreparedScene& scene;
  std::unique_ptr<const Rig> rig;
  std::unique_ptr<const internal::FrameRenderer> frame;  // refers to *rig
  internal::FrameBuffers base;                           // the traced pixels
  std::vector<uint8_t> done;                             // per (level, tile): traced
  int passes = 0;
  internal::FrameBuffers shown;  // the image of the last completed pass
  std::int64_t traced = 0, total = 1;
  double reported = 0;  // last fraction reported (non-decreasing over the frame)
};

ProgressiveRender::ProgressiveRender(const PreparedScene& scene, const Rig& rig,
                                     const RenderView& view, const RenderOptions& options,
                                     const PreparedOverlays* overlays)
    : state_(std::make_unique<State>(scene)) {
  state_->Start(rig, view, options, overlays);
}

void ProgressiveRender::Restart(const Rig& rig, const RenderView& view,
                                const RenderOptions& options, const PreparedOverlays* overlays) {
  state_->Start(rig, view, options, overlays);
}
ProgressiveRender::~ProgressiveRender() = default;
ProgressiveRender::ProgressiveRender(ProgressiveRender&&) noexcept = default;
ProgressiveRender& ProgressiveRender::operator=(ProgressiveRender&&) noexcept = default;

int ProgressiveRender::passes_done() const { return state_->passes; }
const Image& ProgressiveRender::image() const { return state_->shown.image; }

namespace {

// The buffers at full size after the pass of block edge b: pixel (x, y) takes the traced pixel
// nearest to it, (round(x / b) * b, round(y / b) * b), clamped to the last traced row and column.
// Into `out`, whose buffers are reused from pass to pass.
void Upsample(const internal::FrameBuffers& in, int b, internal::FrameBuffers* out_buffers) {
  const Image& src = in.image;
  const int W = src.width, H = src.height;
  internal::FrameBuffers& out = *out_buffers;
  Image& dst = out.image;
  dst.width = W;
  dst.height = H;
  const std::size_t pixels = std::size_t(W) * H;
  dst.rgb.resize(3 * pixels);
  dst.coverage.resize(pixels);
  dst.cameras.resize(src.cameras.size());
  dst.resolution.resize(pixels);
  dst.sigma_max.resize(pixels);
  dst.depth.resize(pixels);
  dst.object.resize(pixels);
  out.normal.resize(in.normal.size());
  const int last_x = ((W - 1) / b) * b, last_y = ((H - 1) / b) * b;
  std::vector<int> source_x(W);
  for (int x = 0; x < W; ++x) source_x[x] = std::min(((x + b / 2) / b) * b, last_x);
  const bool cameras = !src.cameras.empty(), normals = !in.normal.empty();
  tbb::parallel_for(0, H, [&](int y) {
    const int sy = std::min(((y + b / 2) / b) * b, last_y);
    const std::size_t row = std::size_t(y) * W, source_row = std::size_t(sy) * W;
    for (int x = 0; x < W; ++x) {
      const std::size_t p = row + x, q = source_row + source_x[x];
      for (int k = 0; k < 3; ++k) dst.rgb[3 * p + k] = src.rgb[3 * q + k];
      dst.coverage[p] = src.coverage[q];
      if (cameras) dst.cameras[p] = src.cameras[q];
      dst.resolution[p] = src.resolution[q];
      dst.sigma_max[p] = src.sigma_max[q];
      dst.depth[p] = src.depth[q];
      dst.object[p] = src.object[q];
      if (normals) out.normal[p] = in.normal[q];
    }
  });
}

}  // namespace

bool ProgressiveRender::RunPass(const RenderControl& control) {
  State& s = *state_;
  if (s.passes == kPasses) return true;
  const int level = s.passes;
  const internal::FrameRenderer& frame = *s.frame;
  const int tiles = frame.tiles();
  uint8_t* done = s.done.data() + std::size_t(level) * tiles;
  std::atomic<std::int64_t> traced{s.traced};
  std::atomic<bool> stopped{false};
  std::mutex report_mutex;
  const std::int64_t step = std::max<std::int64_t>(1, s.total / 100);
  std::int64_t next_report = s.traced + step;
  // Reports under the mutex, so calls never overlap and their values never decrease.
  auto report = [&](bool end_of_pass) {
    if (!control.progress) return;
    std::unique_lock<std::mutex> lock(report_mutex, std::defer_lock);
    if (end_of_pass) {
      lock.lock();
    } else if (!lock.try_lock()) {
      return;  // another thread is reporting
    }
    const std::int64_t now = traced.load();
    if (!end_of_pass && now < next_report) return;
    next_report = now + step;
    s.reported = std::max(s.reported, double(now) / double(s.total));
    control.progress(s.reported);
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
    const auto scratch = internal::MakeScratch();
    for (int tile = r.begin(); tile != r.end(); ++tile) {
      if (done[tile]) continue;  // traced before a cancellation
      if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
        stopped = true;
        return;
      }
      frame.RenderGroup(tile, level, &s.base, scratch.get(), nullptr, false);
      done[tile] = 1;
      traced += frame.GroupPixels(tile, level);
      report(false);
    }
  });
  s.traced = traced.load();
  if (stopped.load() && !std::all_of(done, done + tiles, [](uint8_t d) { return d != 0; }))
    return false;
  ++s.passes;
  if (s.passes == kPasses) {
    // Every pixel traced: the buffers are Render's before its image-space passes. (The swap keeps
    // the preview's memory in `base` for Restart.)
    std::swap(s.shown, s.base);
  } else {
    Upsample(s.base, BlockSize(level), &s.shown);
  }
  frame.Finish(&s.shown);
  report(true);
  return true;
}

bool ProgressiveRender::RunAll(const RenderControl& control,
                               const std::function<void(const Image&, int pass)>& on_pass) {
  while (!done()) {
    const int pass = passes_done();
    if (!RunPass(control)) return false;
    if (on_pass) on_pass(image(), pass);
  }
  return true;
}

}  // namespace pandora
