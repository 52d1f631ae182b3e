// What the main view draws over the picture: cameras, stations, the slice, the isosurface, the
// gizmo (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::Line(const Projector& P, const Vec3& a, const Vec3& b, ImU32 col,
                           float width) {
  ImVec2 pa, pb;
  if (!P.Segment(a, b, &pa, &pb)) return;
  const double pixels = std::hypot(pb.x - pa.x, pb.y - pa.y);
  const int n = std::clamp(int(pixels / 8.0), 1, 64);
  for (int i = 0; i < n; ++i) {
    const Vec3 p = a + (b - a) * (double(i) / n), q = a + (b - a) * (double(i + 1) / n);
    ImVec2 qa, qb;
    if (P.Segment(p, q, &qa, &qb)) pieces.push_back({0.5 * (p + q), qa, qb, col, width, 0.0f});
  }
}

void ViewerApp::Impl::Dot(const Projector& P, const Vec3& p, ImU32 col, float radius) {
  if (const auto q = P.Point(p)) pieces.push_back({p, *q, *q, col, 0.0f, radius});
}

void ViewerApp::Impl::FlushOverlayPieces(ImDrawList* dl) {
  const Vec3 eye = model.MainView().from;
  std::vector<Ray> rays(pieces.size());
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const Vec3 d = pieces[i].mid - eye;
    const double len = d.norm();
    // Short of the point by a millimetre or 1e-4 of the distance: a line on a wall stays visible.
    rays[i] =
        Ray{eye, d / std::max(len, 1e-12), 0.0, std::max(0.0, len - std::max(1e-3, 1e-4 * len))};
  }
  std::vector<uint8_t> hidden;
  model.session().study().caster().OccludedBatch(rays, &hidden);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const OverlayPiece& p = pieces[i];
    ImU32 col = p.color;
    if (hidden[i])
      col = (col & 0x00FFFFFF) | (ImU32((col >> 24) * 0.3) << 24);  // a third of the opacity
    if (p.radius > 0)
      dl->AddCircleFilled(p.a, hidden[i] ? 0.75f * p.radius : p.radius, col);
    else
      dl->AddLine(p.a, p.b, col, hidden[i] ? std::max(1.0f, 0.7f * p.width) : p.width);
  }
  pieces.clear();
}

void ViewerApp::Impl::DrawOverlays(ImDrawList* dl) {
  const Projector P(model.MainView());
  const Rig& rig = model.rig();
  auto line = [&](const Vec3& a, const Vec3& b, ImU32 col, float width) {
    Line(P, a, b, col, width);
  };
  // The slice: its voxels as translucent quads in the plane.
  if (!model.display.overlays.slice_field.empty()) DrawSlice(dl, P);
  if (!model.display.overlays.iso_field.empty()) DrawIso(dl, P);
  auto frustum = [&](const Camera& cam, ImU32 col, float width) {
    const std::vector<Vec3> border = FrustumBorder(cam, 0.6);
    const Vec3 o = cam.center();
    const std::size_t n = border.size();
    for (std::size_t i = 0; i < n; ++i) line(border[i], border[(i + 1) % n], col, width);
    if (n >= 4)
      for (std::size_t i = 0; i < n; i += n / 4) line(o, border[i], col, width);
  };
  for (int c = 0; c < int(rig.cameras.size()); ++c) {
    const Camera& cam = rig.cameras[c];
    const bool selected = std::count(model.selection.begin(), model.selection.end(), c) > 0;
    const ImU32 col =
        cam.enabled ? Color(cam.color, selected ? 1.0 : 0.8) : IM_COL32(110, 110, 110, 160);
    frustum(cam, col, selected ? 2.5f : 1.2f);
    Dot(P, cam.center(), col, selected ? 6.0f : 4.0f);
    if (const auto p = P.Point(cam.center())) {
      if (selected) dl->AddCircle(*p, 9.0f, IM_COL32(255, 255, 255, 230), 0, 1.5f);
      dl->AddText(ImVec2(p->x + 7, p->y - 7), col, cam.id.c_str());
    }
  }
  if (model.suggestion)
    for (const CameraChange& ch : model.suggestion->cameras) {
      Camera ghost = rig.cameras[ch.index];
      ghost.world_from_camera = ch.after;
      frustum(ghost, IM_COL32(255, 255, 255, 200), 1.5f);
      line(ch.before.translation(), ch.after.translation(), IM_COL32(255, 255, 255, 160), 1.0f);
    }
  DrawStations(dl, P);
  // The suggest panel's keep-out boxes (red) and the box mount (white), while the panel uses
  // them.
  auto box = [&](const float* b, ImU32 col) {
    const Vec3 lo(std::min(b[0], b[3]), std::min(b[1], b[4]), std::min(b[2], b[5]));
    const Vec3 hi(std::max(b[0], b[3]), std::max(b[1], b[4]), std::max(b[2], b[5]));
    auto corner = [&](int k) {
      return Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
    };
    for (int k = 0; k < 8; ++k)
      for (int bit : {1, 2, 4})
        if (!(k & bit)) line(corner(k), corner(k | bit), col, 1.5f);
  };
  for (const auto& k : keep_outs) box(k.data(), IM_COL32(235, 60, 60, 230));
  if (mount == 3) box(mount_box, IM_COL32(240, 240, 240, 200));
  FlushOverlayPieces(dl);
  DrawGizmo(dl, P);  // always on top
}

void ViewerApp::Impl::DrawStations(ImDrawList* dl, const Projector& P) {
  auto line = [&](const Vec3& a, const Vec3& b, ImU32 col, float width) {
    Line(P, a, b, col, width);
  };
  for (const auto& [name, st] : model.stations) {
    CameraView& v = station_views[name];
    const std::int64_t version = model.session().rig().version() * 1000003 + model.stations_version;
    if (!v.texture || v.version != version) {
      Rig rig = model.rig();
      rig.cameras.push_back(DisplayCamera(st));
      RenderView view;
      view.camera = int(rig.cameras.size()) - 1;
      const double scale = std::min(1.0, 320.0 / st.pixels_wide);
      view.width = std::max(16, int(std::lround(st.pixels_wide * scale)));
      view.height = std::max(16, int(std::lround(st.pixels_high * scale)));
      RenderOptions o = InsetOptions();
      o.overlays.cameras = false;
      const Image image = pandora::Render(model.session().study().prepared(), rig, view, o);
      Upload(&v.texture, image.width, image.height, ToRgba8(image.rgb));
      v.version = version;
    }
    const std::array<Vec3, 4> c = DisplayCorners(st);
    std::optional<ImVec2> q[4];
    bool visible = true;
    for (int k = 0; k < 4; ++k) visible &= bool(q[k] = P.Point(c[k]));
    // The textured face only when its front (the viewer's side) faces the main view's eye.
    if (visible && (model.view.Eye() - st.display_center).dot(st.display_normal) > 0)
      dl->AddImageQuad(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(v.texture)), *q[0],
                       *q[1], *q[2], *q[3], ImVec2(0, 0), ImVec2(1, 0), ImVec2(1, 1), ImVec2(0, 1));
    for (int k = 0; k < 4; ++k) {
      line(c[k], c[(k + 1) % 4], IM_COL32(230, 230, 230, 255), 2.0f);
      line(st.eye, c[k], IM_COL32(230, 230, 230, 90), 1.0f);
    }
    if (const auto d = P.Point(st.display_center)) {
      const bool picked = station == name && station_display;
      const float r = picked ? 5.0f : 3.5f;
      dl->AddRectFilled(ImVec2(d->x - r, d->y - r), ImVec2(d->x + r, d->y + r),
                        IM_COL32(255, 255, 255, 255));
    }
    if (const auto e = P.Point(st.eye)) {
      if (station == name && !station_display)
        dl->AddCircle(*e, 8.0f, IM_COL32(255, 255, 255, 230), 0, 1.5f);
      dl->AddCircleFilled(*e, 4.0f, IM_COL32(255, 255, 255, 255));
      dl->AddText(ImVec2(e->x + 6, e->y - 7), IM_COL32(255, 255, 255, 255),
                  (name + " eye").c_str());
    }
    if (st.has_tracker) {
      const std::array<Vec3, 8> t = TrackerCorners(st);
      const ImU32 red = IM_COL32(235, 50, 50, 220);
      for (int k = 0; k < 4; ++k) {
        line(t[k], t[(k + 1) % 4], red, 1.2f);
        line(t[4 + k], t[4 + (k + 1) % 4], red, 1.2f);
        line(t[k], t[4 + k], red, 1.2f);
      }
      line(st.tracker_pose.translation(), t[0], red, 1.0f);
    }
  }
}

void ViewerApp::Impl::DrawSlice(ImDrawList* dl, const Projector& P) {
  const OverlayOptions& ov = model.display.overlays;
  std::int64_t version = -1;
  char key[256];
  std::snprintf(key, sizeof key, "%s %d %.17g", ov.slice_field.c_str(), ov.slice_axis,
                ov.slice_position);
  version = slice_version;
  model.session().TryReadFields([&](const Fields& f, std::int64_t v) {  // busy: keep the last one
    version = v;
    if (v == slice_version && key == slice_key) return;
    try {
      slice = SliceField(f, ov.slice_field, ov.slice_axis,
                         std::isnan(ov.slice_position)
                             ? f.lattice.origin[ov.slice_axis] +
                                   0.5 * f.lattice.voxel_size * (f.lattice.dims[ov.slice_axis] - 1)
                             : ov.slice_position,
                         false);
    } catch (const std::exception&) {
      slice = FieldSlice();
    }
  });
  slice_version = version;
  slice_key = key;
  if (slice.index < 0 || slice.width == 0) return;
  const double h = slice.voxel_size;
  const int ua = slice.u_axis(), va = slice.v_axis();
  const double lo = std::isfinite(ov.slice_min) ? ov.slice_min : slice.min;
  const double hi = std::isfinite(ov.slice_max) ? ov.slice_max : slice.max;
  // Voxels the scene hides from the eye (the ray to the voxel's centre is blocked) at a third of
  // the opacity; tested again only when the view or the slice changes.
  const RenderView view = model.MainView();
  char vkey[512];
  std::snprintf(vkey, sizeof vkey, "%s %lld %.17g %.17g %.17g", key,
                static_cast<long long>(slice_version), view.from.x(), view.from.y(), view.from.z());
  if (vkey != slice_view_key) {
    slice_view_key = vkey;
    std::vector<Ray> rays(std::size_t(slice.width) * slice.height);
    for (int row = 0; row < slice.height; ++row)
      for (int col = 0; col < slice.width; ++col) {
        Vec3 c = Vec3::Zero();
        c[slice.axis] = slice.coordinate;
        c[ua] = slice.u_min + h * col;
        c[va] = slice.v_max - h * row;
        const Vec3 d = c - view.from;
        const double len = d.norm();
        rays[std::size_t(row) * slice.width + col] =
            Ray{view.from, d / std::max(len, 1e-12), 0.0,
                std::max(0.0, len - std::max(1e-3, 1e-4 * len))};
      }
    model.session().study().caster().OccludedBatch(rays, &slice_hidden);
  }
  for (int row = 0; row < slice.height; ++row)
    for (int col = 0; col < slice.width; ++col) {
      const std::size_t o = std::size_t(row) * slice.width + col;
      if (!slice.has_value[o]) continue;
      const double t = hi > lo ? (slice.values[o] - lo) / (hi - lo) : 0.5;
      const Vec3 rgb = ViridisLinear(t);
      Vec3 c = Vec3::Zero();
      c[slice.axis] = slice.coordinate;
      c[ua] = slice.u_min + h * col;
      c[va] = slice.v_max - h * row;
      Vec3 corners[4];
      for (int k = 0; k < 4; ++k) {
        corners[k] = c;
        corners[k][ua] += (k == 1 || k == 2 ? 0.5 : -0.5) * h;
        corners[k][va] += (k >= 2 ? 0.5 : -0.5) * h;
      }
      std::optional<ImVec2> q[4];
      bool ok = true;
      for (int k = 0; k < 4 && ok; ++k) ok = bool(q[k] = P.Point(corners[k]));
      if (ok)
        dl->AddQuadFilled(*q[0], *q[1], *q[2], *q[3],
                          Color(rgb, ov.slice_opacity * (slice_hidden[o] ? 0.33 : 1.0)));
    }
}

void ViewerApp::Impl::DrawIso(ImDrawList* dl, const Projector& P) {
  const OverlayOptions& ov = model.display.overlays;
  char key[256];
  std::snprintf(key, sizeof key, "%s %.17g", ov.iso_field.c_str(), ov.iso_value);
  model.session().TryReadFields([&](const Fields& f, std::int64_t v) {  // busy: keep the last one
    if (v == iso_version && key == iso_key) return;
    iso_version = v;
    iso_key = key;
    iso_view_key.clear();
    try {
      iso_mesh = FieldIsosurface(f, ov.iso_field, ov.iso_value);
    } catch (const std::exception&) {
      iso_mesh = TriangleMesh();
    }
  });
  const std::size_t n = iso_mesh.triangles.size();
  if (n == 0) return;
  const RenderView view = model.MainView();
  char vkey[256];
  std::snprintf(vkey, sizeof vkey, "%.17g %.17g %.17g %d %d", view.from.x(), view.from.y(),
                view.from.z(), view.width, view.height);
  if (vkey != iso_view_key) {
    iso_view_key = vkey;
    std::vector<std::pair<double, int>> depth(n);
    std::vector<Ray> rays(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3i& t = iso_mesh.triangles[i];
      const Vec3 c =
          (iso_mesh.vertices[t[0]] + iso_mesh.vertices[t[1]] + iso_mesh.vertices[t[2]]) / 3.0;
      const double d = (c - view.from).norm();
      depth[i] = {-d, int(i)};
      rays[i] = Ray{view.from, (c - view.from) / std::max(d, 1e-12), 0.0, std::max(0.0, d - 1e-3)};
    }
    std::sort(depth.begin(), depth.end());  // farthest first
    model.session().study().caster().OccludedBatch(rays, &iso_hidden);
    iso_order.resize(n);
    iso_shade.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      iso_order[i] = depth[i].second;
      const Eigen::Vector3i& t = iso_mesh.triangles[depth[i].second];
      const Vec3 a = iso_mesh.vertices[t[0]], b = iso_mesh.vertices[t[1]],
                 c = iso_mesh.vertices[t[2]];
      const Vec3 normal = (b - a).cross(c - a).normalized();
      iso_shade[i] = 0.35 + 0.65 * std::abs(normal.dot(rays[depth[i].second].direction));
    }
  }
  // No anti-aliased fringes: adjacent triangles share their edges, and the fringes would triple
  // the vertices (and show the mesh's edges through the translucency).
  const ImDrawListFlags flags = dl->Flags;
  dl->Flags &= ~ImDrawListFlags_AntiAliasedFill;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i& t = iso_mesh.triangles[iso_order[i]];
    const auto a = P.Point(iso_mesh.vertices[t[0]]), b = P.Point(iso_mesh.vertices[t[1]]),
               c = P.Point(iso_mesh.vertices[t[2]]);
    if (!a || !b || !c) continue;
    const double alpha = ov.iso_opacity * (iso_hidden[iso_order[i]] ? 0.25 : 1.0);
    dl->AddTriangleFilled(*a, *b, *c, Color(iso_shade[i] * ov.iso_color, alpha));
  }
  dl->Flags = flags;
}

void ViewerApp::Impl::DrawGizmo(ImDrawList* dl, const Projector& P) {
  const auto origin = GizmoOrigin();
  if (!origin) return;
  const Vec3 o = *origin;
  const bool rings = !StationPoint();  // a station point only moves
  const double len = GizmoLength();
  const ImU32 axis_col[3] = {IM_COL32(230, 60, 60, 255), IM_COL32(60, 200, 60, 255),
                             IM_COL32(70, 110, 240, 255)};
  for (int k = 0; k < 3; ++k) {
    ImVec2 a, b;
    const bool hot =
        (drag == Drag::kAxis && drag_handle == k) || (drag == Drag::kNone && hover_handle == k);
    if (P.Segment(o, o + len * Vec3::Unit(k), &a, &b))
      dl->AddLine(a, b, axis_col[k], hot ? 4.0f : 2.5f);
    // The ring in the plane normal to axis k.
    if (!rings) continue;
    const Vec3 u = Vec3::Unit((k + 1) % 3), v = Vec3::Unit((k + 2) % 3);
    const bool ring_hot =
        (drag == Drag::kRing && drag_handle == k) || (drag == Drag::kNone && hover_handle == k + 3);
    for (int i = 0; i < 48; ++i) {
      const double t0 = 2 * kPi * i / 48, t1 = 2 * kPi * (i + 1) / 48;
      const Vec3 p0 = o + 0.8 * len * (std::cos(t0) * u + std::sin(t0) * v);
      const Vec3 p1 = o + 0.8 * len * (std::cos(t1) * u + std::sin(t1) * v);
      if (P.Segment(p0, p1, &a, &b))
        dl->AddLine(a, b, axis_col[k] & 0xB0FFFFFF, ring_hot ? 3.5f : 1.5f);
    }
  }
}

}  // namespace pandora::viewer
