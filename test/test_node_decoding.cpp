// The node's input decoding and URDF check, without a ROS master.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "../src/node/command_decoding.hpp"
#include "../src/node/urdf_check.hpp"

namespace {

struct Fixture : ::testing::Test {
  void SetUp() override {
    f3r_scene s = f3r_default_scene();
    for (int i = 0; i < 3; ++i) {
      s.links[i].model = F3R_LINK_FIXED_FREE;
      s.links[i].modes = 2;
    }
    f3r_error err{};
    ASSERT_EQ(f3r_model_create(&s, &model, &err), F3R_OK);
  }
  void TearDown() override { f3r_model_destroy(model); }
  f3r_model* model = nullptr;
  flex3rpr::CommandLimits limits;
  std::vector<double> forces;
};

TEST_F(Fixture, EffortCommandFillsTheGeneralizedForces) {
  flex3rpr::EffortCommand m;
  m.leg_force = {1, 2, 3};
  m.cylinder_torque = {4, 5, 6};
  m.platform = {7, 8, 9};
  m.modal = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  ASSERT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces), "");
  ASSERT_EQ(forces.size(), 15u);
  for (int k = 0; k < 9; ++k) EXPECT_EQ(forces[k], k + 1);
  EXPECT_EQ(forces[14], 0.6);
}

TEST_F(Fixture, BadEffortCommandsNameTheFieldAndChangeNothing) {
  forces.assign(15, 42.0);
  flex3rpr::EffortCommand m;
  m.leg_force[1] = NAN;
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces), "leg_force[1] is NaN");
  m.leg_force[1] = 0;
  m.cylinder_torque[2] = INFINITY;
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces), "cylinder_torque[2] is infinite");
  m.cylinder_torque[2] = 0;
  m.platform[0] = 2e3;
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces), "platform[0] = 2000 exceeds the limit 1000");
  m.platform[0] = 0;
  m.modal = {1.0};
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces), "modal has 1 values, expected 0 or 6");
  for (double f : forces) EXPECT_EQ(f, 42.0);
}

TEST_F(Fixture, EffortGroupFollowsTheJointGroupOrder) {
  std_msgs::Float64MultiArray m;
  m.data = {1, 2, 3, 4, 5, 6};
  ASSERT_EQ(flex3rpr::DecodeEffortGroup(m, *model, limits, &forces), "");
  for (int k = 0; k < 6; ++k) EXPECT_EQ(forces[k], k + 1);
  m.data.pop_back();
  EXPECT_EQ(flex3rpr::DecodeEffortGroup(m, *model, limits, &forces),
            "data has 5 values, expected 6 (leg_force_1..3, cylinder_torque_1..3)");
}

TEST_F(Fixture, WrenchInThePlatformFrameTurnsWithThePlatform) {
  geometry_msgs::WrenchStamped w;
  w.header.frame_id = "platform";
  w.wrench.force.x = 1.0;
  w.wrench.torque.z = 0.5;
  ASSERT_EQ(flex3rpr::DecodeWrench(w, "world", "platform", M_PI / 2, limits, *model, &forces), "");
  EXPECT_NEAR(forces[6], 0.0, 1e-15);
  EXPECT_NEAR(forces[7], 1.0, 1e-15);
  EXPECT_EQ(forces[8], 0.5);
  w.header.frame_id = "moon";
  EXPECT_EQ(flex3rpr::DecodeWrench(w, "world", "platform", 0, limits, *model, &forces),
            "header.frame_id 'moon' is unknown (use 'world' or 'platform')");
  w.header.frame_id = "world";
  w.wrench.torque.x = 0.1;
  EXPECT_EQ(flex3rpr::DecodeWrench(w, "world", "platform", 0, limits, *model, &forces),
            "out-of-plane components (force.z, torque.x, torque.y) must be zero");
}

TEST_F(Fixture, ShippedUrdfMatchesAndAMovedJointIsNamed) {
  std::ifstream in(std::string(F3R_SOURCE_DIR) + "/urdf/flex3rpr.urdf");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string urdf = ss.str();
  ASSERT_FALSE(urdf.empty());
  EXPECT_EQ(flex3rpr::CheckUrdfGeometry(urdf, *model), "");
  f3r_scene s = model->scene;
  s.link_length = 0.21;
  f3r_model* other = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_model_create(&s, &other, &err), F3R_OK);
  const std::string why = flex3rpr::CheckUrdfGeometry(urdf, *other);
  EXPECT_NE(why.find("leg_1_tip_nominal"), std::string::npos) << why;
  EXPECT_NE(why.find("0.21"), std::string::npos) << why;
  f3r_model_destroy(other);
}

}  // namespace

namespace {

TEST(Urdf, PassesCheckUrdfAndIsWhatItsGeneratorWrites) {
  const std::string dir = F3R_SOURCE_DIR;
  EXPECT_EQ(std::system(("check_urdf " + dir + "/urdf/flex3rpr.urdf > /dev/null").c_str()), 0);
  const std::string fresh = "/tmp/f3r_urdf_check.urdf";
  ASSERT_EQ(std::system(("/usr/bin/python3 " + dir + "/scripts/make_urdf.py --out " + fresh).c_str()), 0);
  EXPECT_EQ(std::system(("cmp -s " + fresh + " " + dir + "/urdf/flex3rpr.urdf").c_str()), 0)
      << "urdf/flex3rpr.urdf is out of date: run scripts/make_urdf.py --out urdf/flex3rpr.urdf";
}

}  // namespace
