#pragma once
/// \file options.h
/// Parsing of the command line's list-valued options, shared by the commands: "X,Y,Z" triples,
/// boxes, comma lists, camera ids. Every error is an InputError naming the option (e.g. "--from"),
/// so the one-line message names what the user typed.

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"
#include "render/render.h"

namespace pandora::app {

/// The comma-separated items of `text`, each trimmed of blanks (an empty item stays empty).
std::vector<std::string> SplitList(const std::string& text);

/// Exactly `count` finite numbers separated by commas.
std::vector<double> ParseNumbers(const std::string& option, const std::string& text,
                                 std::size_t count);

/// Three numbers "X,Y,Z" (a point or a direction); the hint shows an example.
Vec3 ParseVec3(const std::string& option, const std::string& text);

/// A box "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX" in metres, within the scene's reach, min <= max.
Aabb ParseBox(const Scene& scene, const std::string& option, const std::string& text);
/// The checks of ParseBox on a box given as values.
void CheckBox(const Scene& scene, const std::string& option, const Aabb& box);

/// The index of camera `id` in `rig`; an unknown id names the option and lists the rig's ids.
int CameraOption(const Rig& rig, const std::string& option, const std::string& id);

/// The scene's view `name` at `width` x `height`; an unknown name names the option and lists the
/// scene's views.
RenderView NamedView(const Scene& scene, const std::string& option, const std::string& name,
                     int width, int height);

/// `text` in lower case (ASCII), for keyword options.
std::string Lower(std::string text);

}  // namespace pandora::app
