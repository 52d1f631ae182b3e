#pragma once
/// \file plot.h
/// Moved: the SVG plots are app/report/plot.h (namespace pandora::report). This forwarding
/// header keeps the commands that still include app/plot.h (suggest_command.cpp) compiling until
/// they include app/report/plot.h themselves; then delete it.

#include "app/report/plot.h"

namespace pandora::app {
using report::BarChart;
using report::BarSeries;
using report::Colorbar;
using report::LogLogPlot;
using report::NiceLabelStep;
using report::NiceStep;
using report::NiceTicks;
using report::PlotMarker;
using report::PlotSeries;
using report::RenderBarChartSvg;
using report::RenderColorbarSvg;
using report::RenderLogLogSvg;
}  // namespace pandora::app
