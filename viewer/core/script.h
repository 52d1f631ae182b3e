#pragma once
/// \file script.h
/// The viewer's actions as data: every UI action (select, move, rotate, enable, zoom a camera,
/// undo, slice, suggest, accept, save, navigate, screenshot) is an Action, whether it came from a
/// click or from a script line, so `pandora view --script FILE` replays what a person does and the
/// unit tests run sessions without GL (docs/viewer.md, "Scripts").
///
/// A script is a JSON array of objects, each naming one action by its first key:
///     [{"select": ["c03"]},
///      {"move": ["c03"], "by": [0.2, 0, 0]},           // world metres; "to": [x, y, z] for one
///      camera
///                                                      // "drag": true continues the last drag
///                                                      step
///      {"rotate": ["c03"], "axis": [0, 0, 1], "deg": 10},  // about the cameras' centroid
///      {"aim": "c03", "at": [0, 0, 1]},                 // turn to look at a point (Z up)
///      {"orient": "c03", "ypr_deg": [30, -10, 0]},      // the scene file's yaw, pitch, roll
///      {"enable": ["c01"]}, {"disable": ["c01"]},
///      {"hfov": ["c03"], "deg": 55},                    // zoom (focal lengths scaled)
///      {"intrinsics": "c03", "resolution": [1280, 720],  // same field of view (fx fy cx cy
///      scaled)
///       "model": "brown_conrady", "k1": -0.1, "k2": 0.01, "p1": 0, "p2": 0, "k3": 0},
///                                                      // fisheye: k1..k4; pinhole: none
///      {"range": "c03", "near": 0.3, "far": 5},         // "far": null: no far limit
///      {"color": "c03", "rgb": [1, 0.2, 0]},             // linear RGB in [0, 1]
///      {"compare": "saved"}, {"compare": ["saved", "grid4x2"]},  // the edited rig against the
///                                                      // rig as saved and / or other rigs
///      {"undo": 1}, {"redo": 1},
///      {"slice": "coverage", "axis": "z", "at": 1.0},   // "slice": "" hides it
///      {"iso": "sigma_max", "value": 2.0},              // "iso": "" hides it
///      {"view": "overview"}, {"orbit": [dx, dy]}, {"pan": [dx, dy]}, {"dolly": 2},
///      {"view": "plan"}, {"view": "elevation", "side": "south"},  // orthographic, cut (pan and
///                                                      // dolly stay in it, orbit leaves it)
///      {"eye": [x, y, z], "at": [x, y, z]},
///      {"light": "grid", "grid": 16, "brightness": 0.5, "surface": "material"},
///      {"wait": "fields"},                              // or "suggest", "render"
///      {"suggest": ["c03"], "objective": "coverage2", "max_move": 0.3, "max_rotate": 10,
///       "points": 600, "seed": 1, "rail": [1, 0, 0],   // or "plane": [0, 0, 1], or "box": [x0,
///       y0, "keep_out": [[x0, y0, z0, x1, y1, z1]],         // z0, x1, y1, z1]; all optional
///       "clearance": 0.1, "hfov_range": [40, 60],
///       "weights": [1, 1, 0], "snap_move": 0.05, "snap_rotate": 5, "outer": 4,
///       "target_surface": ["actor"], "with_region": true,  // or "over_time": true (the
///       },                                              // study's targets at every time sample)
///      {"accept": ["c03"]}, {"accept": "all"}, {"reject": 1},
///      {"save": 1},                                     // {"save": "force"} over a changed file
///      {"screenshot": "out/main.png"}, {"screenshot": "out/c03.png", "camera": "c03"},
///      {"size": [1280, 720]},                           // the main view's size in pixels
///      {"mouse": "press", "button": "left", "x": 640, "y": 360},  // raw input, GL front end only
///      {"mouse": "press", "at": [x, y, z]},   // ... at the pixel where a world point appears
///      {"mouse": "press", "gizmo": "x"},      // ... on the gizmo's x handle (x, y, z; "rx"...
///      rings)
///      {"mouse": "move", "gizmo": "x", "by": 0.25},  // ... where the handle is 0.25 m further
///      {"key": "ctrl+z"}, {"scroll": 1.0, "x": 640, "y": 360},
///      {"gamepad": "c03", "left": [0, -1], "right": [0, 0], "seconds": 0.5},
///      {"frames": 3},                                   // let the window draw
///      {"station": "remote", "eye_at": [x, y, z]},      // move a viewing station's eye
///                                                      // ("display_at": its display's centre)
///      {"ptz": "dome", "pan_deg": 30, "tilt_deg": -10, "hfov_deg": 40},  // a PTZ camera's current
///                                                      // setting (any of the three; clamped)
///      {"ptz": "dome", "preset": "window"},             // ... go to a preset
///      {"recentre": "dome"},                            // home := the current view (docs/ptz.md)
///      {"trace": "path"}, {"trace": "all", "seconds": 1.5}]  // PTZ traces: single, path, all
/// Unknown actions or keys, wrong types and out-of-range values are refused when the script is
/// read, before anything runs: InputError naming the file and the JSON path ("$[4].by").

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora::viewer {

struct Action {
  enum class Kind {
    kSelect,
    kMove,
    kRotate,
    kAim,
    kOrient,
    kEnable,
    kDisable,
    kHfov,
    kIntrinsics,
    kRange,
    kColor,
    kCompare,
    kUndo,
    kRedo,
    kSlice,
    kIso,
    kView,
    kOrbit,
    kPan,
    kDolly,
    kEye,
    kLight,
    kWait,
    kSuggest,
    kAccept,
    kReject,
    kSave,
    kScreenshot,
    kSize,
    kMouse,
    kKey,
    kScroll,
    kGamepad,
    kFrames,
    kStation,
    kPtz,
    kRecentre,
    kTrace,
  };
  Kind kind = Kind::kFrames;
  std::string where;                 ///< "$[i]": for messages while running.
  std::vector<std::string> cameras;  ///< Camera ids (select, move, ... accept; empty accept: all);
                                     ///< compare: "saved" or rig names.
  std::string
      text;  ///< Field, view, wait target, objective, path, key, mouse action, light pattern.
  std::string text2;  ///< slice axis "x"/"y"/"z", surface mode, mouse button, screenshot camera.
  Vec3 a = Vec3::Zero(),
       b = Vec3::Zero();  ///< by/to/axis/at/eye; gamepad left (x, y), right (x, y).
  bool has_a = false, has_b = false;
  double number = 0;   ///< deg, at, value, dolly steps, seconds, frames, scroll, grid, max_move ...
  double number2 = 0;  ///< max_rotate, brightness, mouse y ...
  double number3 = 0;  ///< points, mouse x ...
  bool flag = false;   ///< save "force"; move "to" (absolute); slice/iso hidden; "at" given.
  /// move, rotate, gamepad: part of a drag ("drag": true): continues the previous step of the same
  /// drag (same cameras) as one undo step.
  bool drag = false;
  unsigned long long seed = 1;
  /// intrinsics: the new resolution (0: kept), lens model ("": kept; given, the coefficients not
  /// given are 0) and coefficients k1 k2 p1 p2 k3 k4 (NaN: not given).
  int width = 0, height = 0;
  std::string lens;
  double coefficients[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
  /// range: near and far in metres (NaN: kept; far infinite: no far limit).
  double near = NAN, far = NAN;
  /// suggest: the mount of every selected camera ("", "rail" along `a`, "plane" with normal `a`,
  /// "box" `mount_box`), keep-out boxes, the clearance from surfaces (NaN: the library's default)
  /// and a zoom range in degrees (both 0: none).
  std::string mount;
  Aabb mount_box;
  std::vector<Aabb> keep_out;
  double clearance = NAN;
  double min_hfov = 0, max_hfov = 0;
  /// suggest, as `pandora suggest`'s options of the same names (the same defaults): the mix
  /// weights (NaN: none given), target surfaces (with region points too), the study's targets at
  /// every time sample, snap steps (m, deg; 0: off) and outer iterations.
  Vec3 weights = Vec3::Constant(NAN);
  std::vector<std::string> target_surfaces;
  bool with_region = false, over_time = false;
  double snap_move = 0, snap_rotate = 0;
  int outer_iterations = 4;
  /// mouse: the gizmo handle aimed at (0..2 axes x y z, 3..5 rings; -1: none) and "by" along it
  /// (metres, or degrees on a ring; in `number`); with `has_a`, the world point `a` instead of x,
  /// y.
  int gizmo = -1;
  /// ptz: pan, tilt and horizontal field of view in degrees (NaN: kept) and a preset name ("":
  /// none; the angles are then not given). trace: `text` the mode, `number` the budget (NaN: each
  /// head's trace_s).
  double pan_deg = NAN, tilt_deg = NAN, hfov_deg = NAN;
  std::string preset;
};

/// Parses a script (the text of `path`); throws InputError naming `path` and the JSON path.
std::vector<Action> ParseScript(const std::string& text, const std::string& path);
/// Reads and parses a script file (64 MiB and nesting limits as for scene files).
std::vector<Action> LoadScript(const std::string& path);

}  // namespace pandora::viewer
