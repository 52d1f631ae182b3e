#pragma once
// A GoogleTest helper shared by the tests that check a library's bad-input errors.

#include <gtest/gtest.h>

#include "analysis/util/error.h"

namespace pandora::testing {

/// The InputError `fn` throws; a test failure (and an empty error) when it throws none.
template <class Fn>
InputError ErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return InputError("", "", "");
}

}  // namespace pandora::testing
