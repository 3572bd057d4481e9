// The planner, the field's forces and the sampler for a pack's levels
// (storage::PackLevel), compiled once, optimised, in visvol_pack_planner
// (pack_planner.cpp): the commands that plan, check, sample and draw include
// this, so that their own code builds unoptimised in the sanitizer trees.
#pragma once

#include "rt/rope/planner.hpp"
#include "storage/pack_reader.hpp"

VISVOL_PLANNER_TEMPLATES(extern, visvol::storage::PackLevel)
