#pragma once
#include <cstreams/runtime/error.hpp>

#include <string>

namespace cstreams {

using runtime::Error;

// Bad input from a file or from the caller: the message names the file, line,
// element or object at fault.
class InputError : public Error {
public:
  using Error::Error;
};

}  // namespace cstreams
