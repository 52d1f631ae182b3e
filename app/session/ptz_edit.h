#pragma once
/// \file ptz_edit.h
/// Editing a pan-tilt-zoom camera (docs/ptz.md, "In the viewer"): its file pose is its home at the
/// pivot, its Camera pose the head's current setting. These functions return the edited camera
/// (a new PtzHead copy: Camera::ptz is shared and const) with its pose and focal lengths equal to
/// PtzHead::CameraAt(current); the EditableRig turns them into undo steps. Also the traced rigs of
/// `pandora render --ptz` and the viewer (path: one light per second home -> current; all: the
/// exact renderer's RenderOptions::ptz_all).
///
/// Light header (Eigen, the scene types).

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "analysis/scene/ptz.h"
#include "analysis/scene/scene.h"
#include "render/render.h"

namespace pandora::session {

/// True when both are null or both heads are equal in every field (bit for bit).
bool SamePtzHead(const PtzHead* a, const PtzHead* b);

/// `s` within the head's ranges: pan clamped (wrapped for a continuous pan), tilt clamped, focal
/// clamped to [focal_min, focal_max].
PtzState ClampPtzState(const PtzHead& head, PtzState s);

/// The PTZ camera `camera` at setting `s` (clamped): a new head with current = s, the pose and
/// focal lengths of PtzHead::CameraAt. std::logic_error for a fixed camera.
Camera WithPtzState(const Camera& camera, const PtzState& s);

/// The setting whose optical axis is nearest the orientation `world_from_camera_rotation`'s (not
/// clamped): pan = the axis's azimuth about the pan axis from home's, tilt = its elevation minus
/// home's. A head cannot roll: the orientation's roll is ignored. When the axis is along the pan
/// axis (straight up or down), the pan stays `keep_pan`.
PtzState PtzStateFacing(const PtzHead& head, const Mat3& world_from_camera_rotation,
                        double keep_pan);

/// What a gizmo, a typed position or orientation, an aim or the gamepad asks of a PTZ camera,
/// made mechanical: `requested` is `before` with a new pose (and maybe focal lengths and other
/// attributes). The pivot moves by requested.center() - before.center() (the base is moved); the
/// orientation becomes the pan and tilt facing it (PtzStateFacing, clamped; kept exactly when the
/// rotation did not change); the zoom becomes requested's fx (clamped). The pan axis and home
/// orientation stay. `clamped` (may be null) is set when a range limited the result.
Camera PtzFollow(const Camera& before, const Camera& requested, bool* clamped = nullptr);

/// "Re-centre": home becomes the current view. New home rotation Rot(pan_axis, pan) · home ·
/// Rot(x, tilt) at the same pivot; the current pan and tilt become 0; presets and the pan and tilt
/// ranges shift by (-pan, -tilt), so every preset's pose (and the camera's) is unchanged. Throws
/// InputError(file, where + ".ptz.tilt_range_deg", ...) when the shifted tilt range would fail the
/// scene reader's check (the optical axis past straight up or down from the new home), and for a
/// fixed camera (where = the camera's JSON path).
Camera RecentredPtz(const Camera& camera, const std::string& file, const std::string& where);

/// The rig `rig` with its enabled PTZ cameras' lights replaced by a trace (docs/ptz.md):
/// "single": unchanged; "path": one light per second of the move home -> current (ids
/// "ID@k", the last "ID@k-end", colour times 1 - 0.6 k / (n - 1)); "all": the camera at home with a
/// RenderOptions::PtzTrace of `budget_s` (NaN: each head's trace_s) appended to `all`.
/// `any` (may be null): whether the rig has an enabled PTZ camera. std::invalid_argument for
/// another mode.
Rig PtzTracedRig(const Rig& rig, const std::string& mode, double budget_s,
                 std::vector<RenderOptions::PtzTrace>* all, bool* any = nullptr);

}  // namespace pandora::session
