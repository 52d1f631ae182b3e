#pragma once
/// \file keywords.h
/// Python's one table from the libraries' option fields to its keyword arguments. A library names
/// an option as `{field}` in an error (analysis/util/error.h); the module's exception translator
/// writes it as the keyword a script passes ("{max_move}" -> "max_move", "{size}" -> "width,
/// height"), so pandora.InputError never names a command-line flag.

#include <string>

namespace pandora::python {

/// The keyword argument of `field`: the table's entry, else the field's own name (Python's
/// keywords are the option structs' field names unless the table says otherwise).
std::string Keyword(const std::string& field);

}  // namespace pandora::python
