// The libraries' option fields as Python's keyword arguments (python/keywords.h).
#include "python/keywords.h"

#include <utility>

namespace pandora::python {

std::string Keyword(const std::string& field) {
  // Only where the keyword differs from the field; a new keyword that does gets its line here.
  static const std::pair<const char*, const char*> kKeywords[] = {
      {"size", "width, height"},  // render(width=, height=)
      {"rigs", "rig"},
  };
  for (const auto& [name, keyword] : kKeywords)
    if (field == name) return keyword;
  return field;
}

}  // namespace pandora::python
