#include "planning/interior_point/barrier_forms.hpp"

#include <algorithm>
#include <cmath>

#include "planning/transcription/node_constraints.hpp"

namespace attitude_planner {

double SlackForm::multiplierLimit(const FixedStepRow& row, double dz, double alpha) const {
  if (dz < 0) alpha = std::min(alpha, -p_.fraction_to_boundary * row.z / dz);
  return alpha;
}

void FreeSlacks::prepare(FixedStepRow& row, double mu, double, bool primal) const {
  // s is a variable: the multiplier stays near μ/s, and the condensation is that of c − s = 0
  // (q = μ/z − c makes ds = gᵀdδ + c − s and dz = (q − gᵀdδ)/D).
  const double kappa = p_.dual_safeguard;
  const double z_primal = mu / row.s;
  row.z = primal ? z_primal : std::min(std::max(row.z, mu / (kappa * row.s)), kappa * z_primal);
  row.D = row.s / row.z;
  row.q = mu / row.z - row.c;
}

double FreeSlacks::rowMerit(const FixedStepRow& row, double mu, double rho, double alpha) const {
  const double s = row.s + alpha * row.ds;
  return -mu * std::log(s) + rho * std::abs(row.c - s);
}

double FreeSlacks::dualStepLimit(const FixedStepRow& row, double dz, double, double alpha) const {
  return multiplierLimit(row, dz, alpha);  // z has no upper bound
}

void FreeSlacks::initialize(FixedStepRow& row, double mu, double, double cap) const {
  row.s = std::max(row.c, p_.slack_push);
  row.ds = 0.0;
  row.z = std::min(mu / row.s, cap);
}

void FreeSlacks::addComplementarity(const FixedStepRow& row, double, double, double* sum,
                                    double* low, int* count) const {
  *sum += row.s * row.z;
  *low = std::min(*low, row.s * row.z);
  ++*count;
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

void L1Elastic::prepare(FixedStepRow& row, double mu, double rho, bool primal) const {
  prepareElasticRow(row, mu, rho, primal, p_);
}

double L1Elastic::rowMerit(const FixedStepRow& row, double mu, double rho, double) const {
  return elasticSlacks(row.c, mu, rho).psi;
}

double L1Elastic::dualStepLimit(const FixedStepRow& row, double dz, double rho,
                                double alpha) const {
  return elasticDualStepLimit(row.z, dz, rho, alpha, p_);
}

void L1Elastic::initialize(FixedStepRow& row, double mu, double rho, double cap) const {
  const ElasticSlacks sl = elasticSlacks(row.c, mu, rho);
  row.z = std::min(mu / sl.s, std::min(cap, 0.5 * rho));
}

void L1Elastic::addComplementarity(const FixedStepRow& row, double mu, double rho, double* sum,
                                   double* low, int* count) const {
  const ElasticSlacks sl = elasticSlacks(row.c, mu, rho);
  const double a = sl.s * row.z, b = sl.v * (rho - row.z);
  *sum += a + b;
  *low = std::min(*low, std::min(a, b));
  *count += 2;
}

std::unique_ptr<SlackForm> makeSlackForm(Formulation formulation,
                                         const InteriorPointParameters& parameters) {
  if (formulation == Formulation::FreeSlacks) return std::make_unique<FreeSlacks>(parameters);
  return std::make_unique<L1Elastic>(parameters);
}

double Feasible::safeguarded(double z, double c, double mu) const {
  const double kappa = p_.dual_safeguard;
  return std::clamp(z, mu / (kappa * c), kappa * mu / c);
}

void Feasible::addRowMerit(double c, double c_old, double mu, bool check_boundary, bool* inside,
                           double* phi) const {
  const double fraction = 1 - p_.fraction_to_boundary;
  if (!(c > 0) || (check_boundary && c < fraction * c_old)) *inside = false;
  if (*inside) *phi -= mu * std::log(c);
}

double Feasible::dualDirection(double z, double c, double mu, double slope, double* alpha) const {
  const double dz = mu / c - z - z / c * slope;
  if (dz < 0) *alpha = std::min(*alpha, -p_.fraction_to_boundary * z / dz);
  return dz;
}

double Feasible::residual(const std::vector<FreeTimeRows>& rows, double stationarity,
                          double mu) const {
  double worst = stationarity;
  for (const FreeTimeRows& g : rows) {
    for (const FreeTimeRow& in : g.at) worst = std::max(worst, std::abs(in.z * in.c - mu));
  }
  return worst;
}

double Feasible::dualityGap(const std::vector<FreeTimeRows>& rows) const {
  double gap = 0.0;
  for (const FreeTimeRows& g : rows) {
    for (const FreeTimeRow& in : g.at) gap += in.z * in.c;
  }
  return gap;
}

}  // namespace attitude_planner
