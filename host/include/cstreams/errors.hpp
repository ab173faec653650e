#pragma once
#include <cstreams/runtime/error.hpp>

#include <string>

namespace cstreams {

using runtime::Error;
using runtime::InputError;

}  // namespace cstreams
