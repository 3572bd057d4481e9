// The planner for levels held in memory, compiled once (planner.hpp declares
// these extern).
#include "fields/dense_level.hpp"
#include "rt/rope/planner.hpp"

template class visvol::fields::FieldSampler<visvol::fields::DenseLevel>;

namespace visvol::rt {

template class FieldForces<fields::DenseLevel>;
template Result<GlobalPath> global_search<fields::DenseLevel>(const fields::DenseLevel&, const Vec3&, const Vec3&,
                                                              const GlobalSearchParams&);
template Result<PlanResult> plan<fields::DenseLevel>(const std::vector<const fields::DenseLevel*>&, const PlanRequest&,
                                                     const std::function<void(const PlanProgress&)>&);

}  // namespace visvol::rt
