/* Deliberately broken: the registry must report the error with this file and line. */
#include "runtime/common.h"

__kernel void broken(__global uint* out)
{
  out[get_global_id(0)] = undeclared_identifier;
}
