// The square-map stage (paper §4.2) as a whole: map_to_square and the pieces it is made of, for the
// callers that use several of them.
#pragma once

#include "param/boundary.hpp"
#include "param/coarsen.hpp"
#include "param/corners.hpp"
#include "param/density_flow.hpp"
#include "param/density_map.hpp"
#include "param/density_reweighting.hpp"
#include "param/folds.hpp"
#include "param/harmonic.hpp"
#include "param/map_to_square.hpp"
#include "param/multigrid.hpp"
#include "param/multilevel.hpp"
#include "param/slim.hpp"
#include "param/square_map_options.hpp"
