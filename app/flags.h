#pragma once
/// \file flags.h
/// The command line's one table from the libraries' option fields to its flags. A library names an
/// option as `{field}` in an error (analysis/util/error.h); `pandora` and `pandora view` write it
/// as the flag the user typed ("{max_rotate_deg}" -> "--max-rotate") when they print the error.

#include <string>
#include <utility>
#include <vector>

#include "analysis/util/error.h"

namespace pandora::app {

/// Every (field, flag) pair, in no particular order.
const std::vector<std::pair<std::string, std::string>>& CommandLineFlags();

/// The fields no command sets (a library names them for Python and the viewer): the command line
/// writes them as their names.
const std::vector<std::string>& FieldsWithoutFlag();

/// The flag of `field` ("max_move" -> "--max-move"); empty when the table has none.
std::string CommandLineFlag(const std::string& field);

/// `e` with its `{field}` names written as flags (FieldsWithoutFlag as their names).
InputError ForCommandLine(const InputError& e);

}  // namespace pandora::app
