#pragma once
/// \file colormap.h
/// Moved: viridis, Rgb8 and HexColor are analysis/util/color.h, the one colour module. This
/// forwarding header only keeps branches written before the move compiling; include
/// analysis/util/color.h.

#include "analysis/util/color.h"
