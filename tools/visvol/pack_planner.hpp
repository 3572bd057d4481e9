// The planner, the field's forces and the sampler for a pack's levels
// (storage::PackLevel), compiled once, optimised, in visvol_pack_planner
// (pack_planner.cpp): the commands that plan, check, sample and draw include
// this, so that their own code builds unoptimised in the sanitizer trees.
#pragma once

#include "rt/rope/planner.hpp"
#include "storage/pack_reader.hpp"

extern template class visvol::fields::FieldSampler<visvol::storage::PackLevel>;

namespace visvol::rt {

extern template class FieldForces<storage::PackLevel>;
extern template Result<GlobalPath> global_search<storage::PackLevel>(const storage::PackLevel&, const Vec3&,
                                                                     const Vec3&, const GlobalSearchParams&);
extern template Result<PlanResult> plan<storage::PackLevel>(const std::vector<const storage::PackLevel*>&,
                                                            const PlanRequest&,
                                                            const std::function<void(const PlanProgress&)>&);

}  // namespace visvol::rt
