#include "planning/interior_point/barrier_forms.hpp"

#include <algorithm>
#include <cmath>

#include "planning/transcription/node_constraints.hpp"

namespace attitude_planner {

void FreeSlacks::prepare(Row& row, double mu, double, bool primal) const {
  // s is a variable: the multiplier stays near μ/s, and the condensation is that of c − s = 0
  // (q = μ/z − c makes ds = gᵀdδ + c − s and dz = (q − gᵀdδ)/D).
  const double kappa = p_.dual_safeguard;
  const double z_primal = mu / row.s;
  row.z = primal ? z_primal : std::min(std::max(row.z, mu / (kappa * row.s)), kappa * z_primal);
  row.D = row.s / row.z;
  row.q = mu / row.z - row.c;
}

double FreeSlacks::rowMerit(const Row& row, double, double mu, double rho, double alpha,
                            bool) const {
  const double s = row.s + alpha * row.ds;
  return -mu * std::log(s) + rho * std::abs(row.c - s);
}

void FreeSlacks::initialize(Row& row, double mu, double, double cap) const {
  row.s = std::max(row.c, p_.slack_push);
  row.ds = 0.0;
  row.z = std::min(mu / row.s, cap);
}

void FreeSlacks::addComplementarity(const Row& row, double mu, double, Complementarity* out) const {
  out->add(row.s * row.z, mu);
}

template <int Entries>
void prepareElasticRow(ConstraintRow<Entries>& row, double mu, double rho, bool primal,
                       const InteriorPointParameters& p) {
  const double kappa = p.dual_safeguard;
  const ElasticSlacks sl = elasticSlacks(row.c, mu, rho);
  row.s = sl.s;
  row.v = sl.v;
  const double z_primal = mu / row.s;
  if (primal) {
    row.z = z_primal;
  } else {
    row.z = std::min(std::max(row.z, mu / (kappa * row.s)), kappa * z_primal);
    // u = ρ − z stays positive (u → 0 would make D and q infinite).
    const double u_min = std::max(mu / (kappa * row.v), p.elastic_dual_floor * rho);
    row.z = std::min(row.z, rho - u_min);
  }
  const double u = rho - row.z;
  row.D = row.s / row.z + row.v / u;
  row.q = mu / row.z - row.s - mu / u + row.v;
}
template void prepareElasticRow<9>(ConstraintRow<9>&, double, double, bool,
                                   const InteriorPointParameters&);
template void prepareElasticRow<10>(ConstraintRow<10>&, double, double, bool,
                                    const InteriorPointParameters&);

double elasticDualStepLimit(double z, double dz, double rho, double alpha,
                            const InteriorPointParameters& p) {
  if (dz < 0) alpha = std::min(alpha, -p.fraction_to_boundary * z / dz);
  const double u = rho - z;  // u = ρ − z keeps (1 − τ) of itself too
  if (dz > 0) alpha = std::min(alpha, p.fraction_to_boundary * u / dz);
  return alpha;
}

std::unique_ptr<BarrierForm<9>> makeSlackForm(Formulation formulation,
                                              const InteriorPointParameters& parameters) {
  if (formulation == Formulation::FreeSlacks) return std::make_unique<FreeSlacks>(parameters);
  return std::make_unique<L1Elastic<9>>(parameters);
}

double Feasible::rowMerit(const Row& row, double c, double mu, double, double,
                          bool check_boundary) const {
  const double fraction = 1 - p_.fraction_to_boundary;
  if (!(c > 0) || (check_boundary && c < fraction * row.c)) {
    return std::numeric_limits<double>::infinity();
  }
  return -mu * std::log(c);
}

void Feasible::addComplementarity(const Row& row, double mu, double, Complementarity* out) const {
  out->add(row.z * row.c, mu);
}

void Feasible::afterAccept(Row& row, double mu) const {
  const double kappa = p_.dual_safeguard;
  row.z = std::clamp(row.z, mu / (kappa * row.c), kappa * mu / row.c);
}

}  // namespace attitude_planner
