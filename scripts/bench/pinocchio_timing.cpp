// Pinocchio C++ side of scripts/bench/compare_pinocchio.sh.
//
// Usage: pinocchio_timing <urdf> <tip link> [states=1000] [batches=1000] [per_batch=100]
//
// Loads the URDF with pinocchio::urdf::buildModel (fixed base), draws `states` random states
// (q uniform within the position limits, continuous joints in [-pi, pi]; v, a, tau uniform),
// and for each algorithm, after a 100 ms warm-up, times `batches` batches of `per_batch`
// consecutive calls with std::chrono::steady_clock; batch b starts at state b * per_batch
// (mod states), so the batches cycle through all states. The reported figure is the median
// over batches of (batch time / per_batch). Batches are kept short (100 calls: 0.05-0.3 ms)
// on purpose: on a busy machine a long batch almost always contains a preemption, which
// inflates the median of the slower algorithms (ABA, Coriolis) several times over; short
// batches let the median skip them. Output, one line per algorithm on stdout:
//
//   <name> <median ns per call>
//
// with names rnea crba aba jacobian coriolis gravity fk regressor, the same as the Rust timing example
// (crates/dynamics/examples/timing.rs). Information lines go to stderr, prefixed with '#'.
//
// Pinocchio's algorithms are header templates; compiled here without
// PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION they are instantiated in this file with this file's
// flags (-O3 -march=native), which is how Pinocchio is normally benchmarked. Only the URDF
// parser runs inside the prebuilt libpinocchio_parsers. Build it with
// scripts/bench/compare_pinocchio.sh, which also sets -DEIGEN_MAX_ALIGN_BYTES=16
// -DEIGEN_MALLOC_ALREADY_ALIGNED=1 so that Eigen's layout and allocator match the PyPI
// libraries (built for baseline x86-64); without them an AVX build crashes in buildModel.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "pinocchio/algorithm/aba.hpp"
#include "pinocchio/algorithm/crba.hpp"
#include "pinocchio/algorithm/frames.hpp"
#include "pinocchio/algorithm/joint-configuration.hpp"
#include "pinocchio/algorithm/kinematics.hpp"
#include "pinocchio/algorithm/regressor.hpp"
#include "pinocchio/algorithm/rnea.hpp"
#include "pinocchio/multibody.hpp"
#include "pinocchio/parsers/urdf.hpp"

namespace pin = pinocchio;

namespace {

volatile double g_sink = 0.0;  // keeps results observable so nothing is optimised away

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Plan {
  size_t states;     // distinct states, indices 0..states-1
  size_t batches;    // timed batches
  size_t per_batch;  // calls per batch
};

// Median over plan.batches timed batches of the mean ns per call of body(i).
// A template (not std::function) so that the call is inlined into the timed loop.
template <class Body>
double time_ns(const Plan& plan, Body body) {
  const size_t states = plan.states;
  using clock = std::chrono::steady_clock;
  double acc = 0.0;
  // warm-up: caches, branch predictors, CPU frequency
  const auto warm_until = clock::now() + std::chrono::milliseconds(100);
  while (clock::now() < warm_until)
    for (size_t i = 0; i < states; ++i) acc += body(i);
  std::vector<double> per_call;
  per_call.reserve(plan.batches);
  size_t start = 0;
  for (size_t b = 0; b < plan.batches; ++b) {
    const auto t0 = clock::now();
    for (size_t k = 0, i = start; k < plan.per_batch; ++k) {
      acc += body(i);
      if (++i == states) i = 0;
    }
    const auto t1 = clock::now();
    per_call.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() /
                       static_cast<double>(plan.per_batch));
    start = (start + plan.per_batch) % states;
  }
  g_sink = g_sink + acc;
  return median(per_call);
}

template <class Body>
void report(const char* name, const Plan& plan, Body body) {
  std::printf("%s %.1f\n", name, time_ns(plan, body));
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s <urdf> <tip link> [states=1000] [batches=1000] [per_batch=100]\n",
                 argv[0]);
    return 2;
  }
  const std::string urdf = argv[1];
  const std::string tip = argv[2];
  Plan plan;
  plan.states = argc > 3 ? std::strtoul(argv[3], nullptr, 10) : 1000;
  plan.batches = argc > 4 ? std::strtoul(argv[4], nullptr, 10) : 1000;
  plan.per_batch = argc > 5 ? std::strtoul(argv[5], nullptr, 10) : 100;
  if (plan.states == 0 || plan.batches == 0 || plan.per_batch == 0) {
    std::fprintf(stderr, "states, batches and per_batch must be positive integers\n");
    return 2;
  }
  const size_t states = plan.states;

  pin::Model model;
  pin::urdf::buildModel(urdf, model);
  model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.81));
  if (!model.existFrame(tip, pin::BODY)) {
    std::fprintf(stderr, "no link named '%s' in %s\n", tip.c_str(), urdf.c_str());
    return 2;
  }
  const pin::FrameIndex tip_id = model.getFrameId(tip, pin::BODY);
  pin::Data data(model);

  // random states (fixed seed)
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd lower = model.lowerPositionLimit, upper = model.upperPositionLimit;
  for (Eigen::Index k = 0; k < lower.size(); ++k) {
    if (!std::isfinite(lower[k]) || lower[k] < -1e10) lower[k] = -M_PI;
    if (!std::isfinite(upper[k]) || upper[k] > 1e10) upper[k] = M_PI;
  }
  std::vector<Eigen::VectorXd> Q, V, A, T;
  for (size_t i = 0; i < states; ++i) {
    Q.push_back(pin::randomConfiguration(model, lower, upper));
    Eigen::VectorXd v(model.nv), a(model.nv), t(model.nv);
    for (int k = 0; k < model.nv; ++k) {
      v[k] = 2.0 * unit(rng);
      a[k] = 5.0 * unit(rng);
      t[k] = 10.0 * unit(rng);
    }
    V.push_back(v);
    A.push_back(a);
    T.push_back(t);
  }
  pin::Data::Matrix6x J = pin::Data::Matrix6x::Zero(6, model.nv);

  std::fprintf(stderr,
               "# pinocchio %s: %s, nq=%d nv=%d, tip '%s' (frame %zu), %zu states, %zu batches x %zu calls\n",
               PINOCCHIO_VERSION, urdf.c_str(), model.nq, model.nv, tip.c_str(),
               static_cast<size_t>(tip_id), plan.states, plan.batches, plan.per_batch);

  report("rnea", plan,
         [&](size_t i) { return pin::rnea(model, data, Q[i], V[i], A[i])[0]; });
  report("crba", plan,
         [&](size_t i) { return pin::crba(model, data, Q[i])(0, model.nv - 1); });
  report("aba", plan,
         [&](size_t i) { return pin::aba(model, data, Q[i], V[i], T[i])[0]; });
  report("jacobian", plan, [&](size_t i) {
    pin::computeFrameJacobian(model, data, Q[i], tip_id, pin::LOCAL_WORLD_ALIGNED, J);
    return J(0, 0);
  });
  report("coriolis", plan,
         [&](size_t i) { return pin::computeCoriolisMatrix(model, data, Q[i], V[i])(0, 0); });
  report("gravity", plan,
         [&](size_t i) { return pin::computeGeneralizedGravity(model, data, Q[i])[0]; });
  report("fk", plan, [&](size_t i) {
    pin::forwardKinematics(model, data, Q[i]);
    pin::updateFramePlacements(model, data);
    return data.oMf[tip_id].translation()[0];
  });
  report("regressor", plan, [&](size_t i) {
    return pin::computeJointTorqueRegressor(model, data, Q[i], V[i], A[i])(0, 0);
  });

  // One state through RNEA for a cross-check against the JSON fixtures (stderr only).
  Eigen::VectorXd q0 = pin::neutral(model), v0 = Eigen::VectorXd::Zero(model.nv);
  std::fprintf(stderr, "# check: |g(neutral)| = %.12g\n",
               pin::rnea(model, data, q0, v0, v0).norm());
  return 0;
}
