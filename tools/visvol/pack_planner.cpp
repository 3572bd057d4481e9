#include "pack_planner.hpp"

VISVOL_PLANNER_TEMPLATES(, visvol::storage::PackLevel)
