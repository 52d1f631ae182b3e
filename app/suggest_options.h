#pragma once
/// \file suggest_options.h
/// `pandora suggest`'s options turned into the library's SuggestOptions: the selection by camera
/// id, per-camera limits ("one value, or one per selected camera"), mounts and zoom ranges ("ID:"
/// prefixes), keep-out boxes, the objective. Every error names the option the user typed.

#include "app/commands.h"
#include "app/session/session.h"
#include "suggest/suggest.h"

namespace pandora::app {

/// The session of a suggest run: the scene file, --rig and --disable.
session::SessionOptions SuggestSessionOptions(const SuggestArgs& args);

SuggestOptions SuggestOptionsFromArgs(const SuggestArgs& args, const Scene& scene, const Rig& rig);

}  // namespace pandora::app
