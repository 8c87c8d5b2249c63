// The simulated bench's one request (jobs/measure/sim_bench.hpp): its defaults
// are the acquisition's (measure and sim-instrument without options simulate
// what they did before), the demo's is the seed's target tube, and a bad
// effect or disturbance is refused naming it.
#include <gtest/gtest.h>

#include "jobs/demo_job.hpp"
#include "jobs/measure/sim_bench.hpp"

using namespace piezo;

TEST(SimBench, DefaultsAreTheAcquisitionsSpec) {
  const acq::SimSpec s = jobs::sim_spec(jobs::SimBenchRequest{});
  const acq::SimSpec d;
  EXPECT_EQ(s.material, d.material);
  EXPECT_EQ(s.isotropic, d.isotropic);
  EXPECT_EQ(s.set, d.set);
  EXPECT_EQ(s.damping.alpha, d.damping.alpha);
  EXPECT_EQ(s.damping.beta, d.damping.beta);
  EXPECT_EQ(s.noise_rel, d.noise_rel);
  EXPECT_EQ(s.seed, d.seed);
  EXPECT_EQ(s.adc_bits, d.adc_bits);
  EXPECT_EQ(s.geometry.outer_diameter_m, d.geometry.outer_diameter_m);
}

TEST(SimBench, TheDemoIsTheSeedsTargetTubeWithItsOptions) {
  jobs::DemoRequest demo;
  demo.noise = 0.02;
  demo.seed = 7;
  demo.effects = {"series_resistance=15"};
  demo.disturbances = "offset=0.005";
  const auto r = jobs::demo_sim_request(demo);
  EXPECT_TRUE(r.isotropic);
  EXPECT_EQ(r.set, "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294");
  const acq::SimSpec s = jobs::demo_bench_request(demo).sim;
  EXPECT_EQ(s.noise_rel, 0.02);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.set, r.set);
  EXPECT_NE(s.disturbances.offset_v, 0.0);
}

TEST(SimBench, BadItemsAreRefusedAndThePanelsTextIsSplit) {
  jobs::SimBenchRequest r;
  r.effects = {"no_such_effect=1"};
  EXPECT_THROW(jobs::sim_spec(r), std::invalid_argument);
  r.effects.clear();
  r.disturbance = "nope=1";
  EXPECT_THROW(jobs::sim_spec(r), std::invalid_argument);
  EXPECT_EQ(jobs::split_sim_effects(" series_resistance=15 ,, channel_skew=1e-7"),
            (std::vector<std::string>{"series_resistance=15", "channel_skew=1e-7"}));
}
