// The command line's frame (app/cli.h): the number check and the empty-value refusal every
// command's options use.
#include "app/cli.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pandora::app {

namespace {

std::string Short(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

}  // namespace

CLI::Validator Number(double min, double max, const std::string& unit, bool whole,
                      bool min_exclusive, bool max_exclusive) {
  const std::string kind = whole ? "a whole number" : "a number";
  std::string range;
  if (std::isinf(min) && std::isinf(max))
    range = "finite";
  else if (std::isinf(max))
    range = min_exclusive ? "greater than " + Short(min) : "at least " + Short(min);
  else if (std::isinf(min))
    range = max_exclusive ? "less than " + Short(max) : "at most " + Short(max);
  else
    range = std::string("in ") + (min_exclusive ? "(" : "[") + Short(min) + ", " + Short(max) +
            (max_exclusive ? ")" : "]");
  const std::string expected = "must be " + kind + " of " + unit + ", " + range;
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        errno = 0;
        const double v =
            whole ? static_cast<double>(std::strtoll(begin, &end, 10)) : std::strtod(begin, &end);
        if (text.empty() || end == begin || *end != '\0') return expected + ", got '" + text + "'";
        if (errno == ERANGE || !std::isfinite(v)) return expected + ", got " + text;
        if (v < min || v > max || (min_exclusive && v == min) || (max_exclusive && v == max))
          return expected + ", got " + text;
        return "";
      },
      "", "number");
}

void RefuseEmptyValues(CLI::App* app) {
  for (CLI::Option* option : app->get_options()) {
    if (option->get_type_size() == 0) continue;  // a flag
    option->check(CLI::Validator(
        [](std::string& text) -> std::string {
          return text.empty() ? std::string(
                                    "the value is empty (an empty value is not the default; leave "
                                    "the option out)")
                              : std::string();
        },
        "", "non-empty"));
  }
  for (CLI::App* sub : app->get_subcommands({})) RefuseEmptyValues(sub);
}

}  // namespace pandora::app
