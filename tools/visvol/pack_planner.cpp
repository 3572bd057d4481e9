#include "pack_planner.hpp"

template class visvol::fields::FieldSampler<visvol::storage::PackLevel>;

namespace visvol::rt {

template class FieldForces<storage::PackLevel>;
template Result<GlobalPath> global_search<storage::PackLevel>(const storage::PackLevel&, const Vec3&, const Vec3&,
                                                              const GlobalSearchParams&);
template Result<PlanResult> plan<storage::PackLevel>(const std::vector<const storage::PackLevel*>&, const PlanRequest&,
                                                     const std::function<void(const PlanProgress&)>&);

}  // namespace visvol::rt
