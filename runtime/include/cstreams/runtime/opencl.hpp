#pragma once
// The one place the OpenCL API version is fixed: OpenCL 1.2 is what NVIDIA's driver
// offers for OpenCL C, so nothing newer may be called.
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl.h>
