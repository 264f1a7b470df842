// Each baseline does what METHOD.md §b documents for it, measured on a handful of hand-placed particles through
// the hooks the solver calls: thuerey's attraction fades as a control particle fills; pbfc's spring acts only on
// escaping particles; weighted pulls harder toward a sparse control particle; rscf pulls whatever the fill; lcat
// spawns temporaries into an empty template, up to τ N_T and no more.
#include "control/registry.h"
#include "sampling/weights.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff {
namespace {

constexpr float kR = 0.025f, kD = 2 * kR, kHc = 2 * kD;  // particle radius, spacing, control support

control::ControlContext context() {
  control::ControlContext ctx;
  ctx.particle_radius = kR;
  ctx.particle_mass = 1000.0f * kD * kD * kD;
  ctx.fluid_support = 2 * kD;
  return ctx;
}

// A control set at the given positions with the density a full neighbourhood has.
sampling::ControlSet make_set(const std::vector<Vec3f>& x) {
  sampling::ControlSet s;
  s.resize(x.size());
  s.position = x;
  const float rho = static_cast<float>(sampling::lattice_density(kD, kHc, 1000.0f));
  for (std::size_t i = 0; i < x.size(); ++i) s.density[i] = rho, s.weight[i] = 1.0f, s.phi[i] = 1.0f;
  s.spacing = kD, s.support = kHc, s.mass = 1000.0f * kD * kD * kD;
  return s;
}

std::unique_ptr<sim::Controller> make(const control::ControllerSpec& spec, const sampling::ControlSet& set) {
  std::vector<control::ControlTarget> t(1);
  t[0].set = set;
  auto c = control::make_controller(spec, std::move(t), context());
  EXPECT_TRUE(c.has_value()) << (c ? "" : c.error().message);
  return c ? std::move(*c) : nullptr;
}

void add(sim::ParticleSet& p, const Vec3f& x) {
  p.push_back(x, Vec3f::Zero(), 0);
  p.density.back() = 1000.0f;
}

sim::StepView step_view() { return sim::StepView{1.0f / 120.0f, 0.0, -1, 4, kR, nullptr}; }

// The acceleration the controller gives particle 0 in one sub-step.
Vec3f acceleration_of_first(sim::Controller& c, sim::ParticleSet& p) {
  for (auto& a : p.acceleration) a = Vec3f::Zero();
  const auto v = step_view();
  c.begin_step(v, p);
  c.add_accelerations(v, p);
  return p.acceleration[0];
}

// Particles on a lattice of spacing d filling the ball of radius `radius` about `centre`, but not at `skip`.
void fill_ball(sim::ParticleSet& p, const Vec3f& centre, float radius, const Vec3f& skip) {
  const int k = static_cast<int>(std::ceil(radius / kD));
  for (int z = -k; z <= k; ++z)
    for (int y = -k; y <= k; ++y)
      for (int x = -k; x <= k; ++x) {
        const Vec3f q = centre + kD * Vec3f(float(x), float(y), float(z));
        if ((q - centre).norm() <= radius && (q - skip).norm() > 0.5f * kD) add(p, q);
      }
}

TEST(Thuerey, AttractionFadesAsTheControlParticleFills) {
  control::ControllerSpec spec;
  spec.name = "thuerey";
  const auto set = make_set({Vec3f::Zero()});
  const Vec3f probe(0.6f * kHc, 0, 0);
  auto c = make(spec, set);
  sim::ParticleSet empty;
  add(empty, probe);
  const Vec3f a_empty = acceleration_of_first(*c, empty);
  sim::ParticleSet full;
  add(full, probe);
  fill_ball(full, Vec3f::Zero(), 0.75f * kHc, probe);
  const Vec3f a_full = acceleration_of_first(*c, full);
  EXPECT_LT(a_empty.x(), 0.0f) << "pulled toward the control particle";
  // |A| = q, Ω = q w_a(0.6 R_a) = 0.8 q, a = α Ω |A|; the probe itself fills the control particle a little:
  // q = 1 − 0.8/N_full, N_full = (4/3)π (0.75 R_a)³/d³.
  const float n_full = 4.0f / 3.0f * 3.14159265f * std::pow(0.75f * kHc / kD, 3.0f), q = 1.0f - 0.8f / n_full;
  EXPECT_NEAR(a_empty.norm(), spec.get<control::ThuereyParams>().attraction * 0.8f * q * q, 1e-3f * spec.get<control::ThuereyParams>().attraction);
  EXPECT_LT(a_full.norm(), 0.05f * a_empty.norm()) << "a full control particle (q = 0) attracts nothing";
}

TEST(Pbfc, SpringActsOnlyOnEscapingParticles) {
  control::ControllerSpec spec;
  spec.name = "pbfc";
  spec.get<control::PbfcParams>().alpha = 0.0f;     // spring alone
  spec.get<control::PbfcParams>().velocity = 0.0f;
  auto c = make(spec, make_set({Vec3f::Zero()}));
  sim::ParticleSet p;
  add(p, Vec3f(0.3f * kHc, 0, 0));  // within D/2: takes the control particle as its reference
  auto v = step_view();
  auto step = [&](const Vec3f& at) {
    p.position[0] = p.predicted[0] = at;
    c->begin_step(v, p);
    v.iteration = 0;
    c->correct_positions(v, p);
    v.iteration = -1;
    return Vec3f(p.predicted[0] - at);
  };
  const Vec3f near = step(Vec3f(0.3f * kHc, 0, 0));
  EXPECT_LT(near.norm(), 1e-4f * kD) << "no spring near the reference";
  const Vec3f away = step(Vec3f(2.0f * kHc, 0, 0));  // escaped beyond b = 1.5 H_c: σ ≈ 1
  EXPECT_NEAR(away.norm(), spec.get<control::PbfcParams>().spring * kD, 0.02f * kD);
  EXPECT_LT(away.x(), 0.0f) << "pulled back toward its reference";
  for (int k = 0; k < 3; ++k) step(Vec3f(2.0f * kHc, 0, 0));
  const Vec3f expired = step(Vec3f(2.0f * kHc, 0, 0));
  EXPECT_EQ(expired.norm(), 0.0f) << "the spring lives T = 3 sub-steps after the particle left";
}

TEST(Weighted, PullsHarderTowardASparseControlParticle) {
  // A dense block of samples and one lone sample far away: the lone one's colour field is the lowest (only its
  // own kernel), so its weight is 1 + κ(1 − cf/max cf), close to 1 + κ: a probe next to it moves that much
  // farther than with κ = 0.
  std::vector<Vec3f> x;
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 6; ++y)
      for (int i = 0; i < 6; ++i) x.push_back(kD * Vec3f(float(i), float(y), float(z)));
  const Vec3f lone(2.0f, 0, 0);
  x.push_back(lone);
  auto move = [&](float kappa) {
    control::ControllerSpec spec;
    spec.name = "weighted";
    spec.get<control::WeightedParams>().kappa = kappa;
    spec.get<control::WeightedParams>().spring = 0.0f;
    auto c = make(spec, make_set(x));
    sim::ParticleSet p;
    add(p, lone + Vec3f(0.5f * kHc, 0, 0));
    auto v = step_view();
    p.predicted[0] = p.position[0];
    c->begin_step(v, p);
    v.iteration = 0;
    c->correct_positions(v, p);
    return Vec3f(p.predicted[0] - p.position[0]);
  };
  const Vec3f plain = move(0.0f), weighted = move(1.0f);
  EXPECT_LT(plain.x(), 0.0f);
  EXPECT_GT(weighted.norm() / plain.norm(), 1.5f);
  EXPECT_LE(weighted.norm() / plain.norm(), 2.0f + 1e-5f);
}

TEST(Rscf, PullsWhateverTheFill) {
  // No density term: the rig pulls a particle the same whether its neighbourhood is empty or full.
  control::ControllerSpec spec;
  spec.name = "rscf";
  std::vector<Vec3f> rig;
  for (int i = -2; i <= 2; ++i) rig.push_back(kD * Vec3f(float(i), 0, 0));
  auto c = make(spec, make_set(rig));
  const Vec3f probe(0, 0.5f * kHc, 0);
  sim::ParticleSet empty;
  add(empty, probe);
  const Vec3f a_empty = acceleration_of_first(*c, empty);
  sim::ParticleSet full;
  add(full, probe);
  fill_ball(full, Vec3f::Zero(), kHc, probe);
  const Vec3f a_full = acceleration_of_first(*c, full);
  EXPECT_LT(a_empty.y(), 0.0f) << "toward the rig";
  EXPECT_EQ(a_empty, a_full);
}

TEST(Lcat, SpawnsTemporariesIntoAnEmptyTemplateUpToItsShare) {
  std::vector<Vec3f> x;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 5; ++y)
      for (int i = 0; i < 4; ++i) x.push_back(kD * Vec3f(float(i), float(y), float(z)));  // N_T = 100
  control::ControllerSpec spec;
  spec.name = "lcat";
  auto c = make(spec, make_set(x));
  sim::ParticleSet p;
  add(p, Vec3f(5, 5, 5));  // far away: the template is empty
  auto v = step_view();
  c->begin_step(v, p);
  c->emit(v, p);
  const auto cap = static_cast<std::size_t>(std::floor(spec.get<control::LcatParams>().temporaries * 100.0f));
  EXPECT_EQ(p.size(), 1 + cap) << "τ N_T temporaries at the first sub-step (every sample is empty)";
  EXPECT_TRUE(p.consistent());
  EXPECT_EQ(p.position[1], x[0]) << "spawned at the template particle";
  c->begin_step(v, p);
  c->emit(v, p);
  EXPECT_EQ(p.size(), 1 + cap) << "never more than τ N_T";
}

}  // namespace
}  // namespace ff
