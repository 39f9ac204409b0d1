// Writing the result: OBJ + MTL + texture images, atomically (write_obj, declared in tightex/io.hpp).
#pragma once
#include <string>

#include "core/mesh.hpp"
#include "io/image_io.hpp"
#include "tightex/io.hpp"

namespace tightex {

/// Shortest text that reads back as exactly `value`.
std::string format_double(double value);

}  // namespace tightex
