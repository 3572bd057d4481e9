// The planner for levels held in memory, compiled once (planner.hpp declares
// these extern).
#include "fields/dense_level.hpp"
#include "rt/rope/planner.hpp"

VISVOL_PLANNER_TEMPLATES(, visvol::fields::DenseLevel)
