#pragma once
/// \file progressive.h
/// Progressive rendering for interactive use: a coarse image first (one traced pixel per 8 x 8
/// block, shown as blocks), then passes that trace the pixels the previous passes left out (one
/// per 4 x 4, then per 2 x 2 block, then the rest), so a viewer shows something within about a
/// sixty-fourth of a frame and refines while idle. Each pass can be cancelled between tiles and
/// resumed; progress is reported as the share of the frame's pixels traced. Every pixel is traced
/// once over the four passes, exactly as Render traces it, so the last pass's image equals
/// Render(prepared, rig, view, options, overlays) bit for bit.

#include <atomic>
#include <functional>
#include <memory>

#include "render/render.h"

namespace pandora {

/// Cancellation and progress of a pass (both optional).
struct RenderControl {
  /// Read before each tile (16 x 16 pixels at one pass); once it reads true no further tile starts
  /// and the pass returns false. Tiles already running finish (a tile takes well under a
  /// millisecond to a few milliseconds).
  const std::atomic<bool>* cancel = nullptr;
  /// Called with the share of the frame's pixels traced so far, in [0, 1] over all passes, every
  /// percent or so and at the end of a pass. Called from TBB worker threads, one call at a time,
  /// with non-decreasing values; it must be cheap and must not call back into the renderer.
  std::function<void(double fraction)> progress;
};

/// A frame rendered in passes. Owns a copy of the rig, view and options; `scene` (and `overlays`
/// when given) must outlive it. Not thread-safe itself (one thread runs the passes and reads the
/// image), but each pass runs in parallel over tiles (TBB).
class ProgressiveRender {
 public:
  /// The number of passes.
  static constexpr int kPasses = 4;
  /// Block edge of pass `pass` (0-based): 8, 4, 2, 1 pixels. After pass p every pixel whose x and
  /// y are multiples of BlockSize(p) is traced; the others show the traced pixel nearest to them
  /// (the one at round(x / b) * b, clamped into the image: blocks centred on their sample).
  static int BlockSize(int pass) { return 8 >> pass; }

  /// Checks the view and the overlays as Render does (and throws as Render does); traces nothing.
  ProgressiveRender(const PreparedScene& scene, const Rig& rig, const RenderView& view,
                    const RenderOptions& options, const PreparedOverlays* overlays = nullptr);
  ~ProgressiveRender();
  ProgressiveRender(ProgressiveRender&&) noexcept;
  ProgressiveRender& operator=(ProgressiveRender&&) noexcept;

  /// Starts a new frame of the same prepared scene with another rig, view, options or overlays
  /// (a camera moved, the eye moved, ...), as a new ProgressiveRender would, but keeping the
  /// image buffers when the size is unchanged, so the first pass of the next frame does not wait
  /// for fresh memory. What a viewer calls after each edit once the running pass was cancelled.
  /// Throws as the constructor does, and then leaves the current frame as it was.
  void Restart(const Rig& rig, const RenderView& view, const RenderOptions& options,
               const PreparedOverlays* overlays = nullptr);

  /// Runs the next pass and updates image(). Returns true when the pass completed (or all passes
  /// were already done), false when control.cancel stopped it: image() then still shows the last
  /// completed pass, and the next call resumes the pass, tracing only the tiles still missing.
  bool RunPass(const RenderControl& control = {});
  /// Runs the remaining passes; `on_pass` (may be empty) is called after each with the image and
  /// the pass's index. Returns false when cancelled.
  bool RunAll(const RenderControl& control = {},
              const std::function<void(const Image&, int pass)>& on_pass = {});

  /// Passes completed, 0 .. kPasses.
  int passes_done() const;
  bool done() const { return passes_done() == kPasses; }
  /// The latest completed pass at full size with overlays, key and contours (width and height 0
  /// before the first pass). After the last pass: equal to Render's image bit for bit, every layer
  /// included.
  const Image& image() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace pandora
