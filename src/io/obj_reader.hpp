// Reading Wavefront OBJ + MTL, with every texture image the materials name.
//
// tightex parses OBJ itself rather than through tinyobjloader: a pipeline that runs unattended over
// thousands of scans needs every malformed line refused with its file and line number, which
// tinyobjloader's loader does not give for bad indices or numbers.
#pragma once
#include <string>
#include <vector>

#include "core/mesh.hpp"
#include "tightex/io.hpp"
