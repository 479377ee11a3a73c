// The node's input decoding and URDF check, without a ROS master.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <urdf_parser/urdf_parser.h>

#include "../src/node/command_decoding.hpp"
#include "../src/node/pacer.hpp"
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
  const f3r_scene limits = f3r_default_scene();  // the scene's limits section: 1000 N, 100 N m
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
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces),
            "leg_force_2 is nan, not finite");
  m.leg_force[1] = 0;
  m.cylinder_torque[2] = INFINITY;
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces),
            "cylinder_torque_3 is inf, not finite");
  m.cylinder_torque[2] = 0;
  m.platform[0] = 2e3;
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces),
            "platform_force_x is 2000, out of range -1000..1000 (the scene's limits.force)");
  m.platform[0] = 0;
  m.modal = {0, 0, 0, 0, 1e4, 0};
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces),
            "modal_force[4] is 10000, out of range -1000..1000 (the scene's limits.modal_force)");
  m.platform[0] = 0;
  m.modal = {1.0};
  EXPECT_EQ(flex3rpr::DecodeEffortCommand(m, *model, limits, &forces),
            "modal has 1 values, expected 0 or 6");
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
  m.data = {1, 2, 3, 4, 500, 6};
  EXPECT_EQ(flex3rpr::DecodeEffortGroup(m, *model, limits, &forces),
            "cylinder_torque_2 is 500, out of range -100..100 (the scene's limits.torque)");
}

TEST_F(Fixture, WrenchInATurnedFrameIsTurnedIntoTheBase) {
  geometry_msgs::WrenchStamped w;
  w.header.frame_id = "platform";
  w.wrench.force.x = 1.0;
  w.wrench.torque.z = 0.5;
  ASSERT_EQ(flex3rpr::DecodeWrench(w, flex3rpr::YawRotation(M_PI / 2), limits, *model, &forces),
            "");
  EXPECT_NEAR(forces[6], 0.0, 1e-15);
  EXPECT_NEAR(forces[7], 1.0, 1e-15);
  EXPECT_EQ(forces[8], 0.5);
  w.wrench.torque.x = 0.1;
  EXPECT_EQ(flex3rpr::DecodeWrench(w, flex3rpr::YawRotation(0.0), limits, *model, &forces),
            "out-of-plane components (force.z, torque.x, torque.y in the base frame) must be zero");
  // A frame upside down (turned by pi about x): its -z is the base's z, so torque.z = -0.5
  // there is +0.5 in the base, and its force.y is the base's -force.y.
  w.wrench.torque.x = 0.0;
  w.wrench.torque.z = -0.5;
  w.wrench.force.y = 2.0;
  const flex3rpr::Rotation flipped = {1, 0, 0, 0, -1, 0, 0, 0, -1};
  ASSERT_EQ(flex3rpr::DecodeWrench(w, flipped, limits, *model, &forces), "");
  EXPECT_EQ(forces[6], 1.0);
  EXPECT_EQ(forces[7], -2.0);
  EXPECT_EQ(forces[8], 0.5);
  // Tilted by a quarter turn about x: the frame's y is the base's z, out of the plane.
  const flex3rpr::Rotation tilted = {1, 0, 0, 0, 0, -1, 0, 1, 0};
  EXPECT_EQ(flex3rpr::DecodeWrench(w, tilted, limits, *model, &forces),
            "out-of-plane components (force.z, torque.x, torque.y in the base frame) must be zero");
}

TEST_F(Fixture, ShippedUrdfMatchesAndAMovedJointIsNamed) {
  std::ifstream in(std::string(F3R_SOURCE_DIR) + "/urdf/flex3rpr.urdf");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string urdf = ss.str();
  ASSERT_FALSE(urdf.empty());
  const flex3rpr::FrameNames frames = flex3rpr::MakeFrameNames("", "world", "base", 11);
  EXPECT_EQ(flex3rpr::CheckUrdf(urdf, *model, &frames), "");
  f3r_scene s = *f3r_model_scene(model); /* a view: rest.yaml has no tables */
  s.link_length = 0.21;
  f3r_model* other = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_model_create(&s, &other, &err), F3R_OK);
  std::string why = flex3rpr::CheckUrdf(urdf, *other, &frames);
  EXPECT_NE(why.find("leg_1_tip_nominal"), std::string::npos) << why;
  EXPECT_NE(why.find("0.21"), std::string::npos) << why;
  f3r_model_destroy(other);
  // The stroke is the prismatic joints' limits.
  s = *f3r_model_scene(model);
  s.stroke_max = 0.25;
  ASSERT_EQ(f3r_model_create(&s, &other, &err), F3R_OK);
  why = flex3rpr::CheckUrdf(urdf, *other, &frames);
  EXPECT_NE(
      why.find("leg_1_prismatic upper limit (geometry.stroke_max) is 0.2 m in the URDF but 0.25"),
      std::string::npos)
      << why;
  f3r_model_destroy(other);
  // Frames the node would publish that the URDF lacks, or stations it has too many of.
  const flex3rpr::FrameNames prefixed =
      flex3rpr::MakeFrameNames("robot1/", "world", "robot1/base", 11);
  why = flex3rpr::CheckUrdf(urdf, *model, &prefixed);
  EXPECT_NE(why.find("lacks link robot1/base"), std::string::npos) << why;
  const flex3rpr::FrameNames fewer = flex3rpr::MakeFrameNames("", "world", "base", 5);
  why = flex3rpr::CheckUrdf(urdf, *model, &fewer);
  EXPECT_NE(why.find("more beam stations than ~beam_points = 5 (link leg_1_beam_5)"),
            std::string::npos)
      << why;
  const flex3rpr::FrameNames more = flex3rpr::MakeFrameNames("", "world", "base", 12);
  why = flex3rpr::CheckUrdf(urdf, *model, &more);
  EXPECT_NE(why.find("lacks link leg_1_beam_11"), std::string::npos) << why;
}

TEST(FramePrefix, IsNormalisedToOneTrailingSlash) {
  EXPECT_EQ(flex3rpr::NormalisePrefix(""), "");
  EXPECT_EQ(flex3rpr::NormalisePrefix("/"), "");
  EXPECT_EQ(flex3rpr::NormalisePrefix("robot1"), "robot1/");
  EXPECT_EQ(flex3rpr::NormalisePrefix("/robot1/"), "robot1/");
  const flex3rpr::FrameNames f = flex3rpr::MakeFrameNames("r/", "world", "r/base", 3);
  EXPECT_EQ(f.beam[2][2], "r/leg_3_beam_2");
  EXPECT_EQ(f.platform_c[0], "r/platform_c1");
  EXPECT_EQ(f.world, "world");
}

}  // namespace

namespace {

std::string Generate(const std::string& args, const std::string& out) {
  const std::string dir = F3R_SOURCE_DIR;
  const std::string cmd = "F3R_CLI=" + std::string(F3R_CLI) + " /usr/bin/python3 " + dir +
                          "/nodes/make_urdf.py " + args + " --out " + out;
  return std::system(cmd.c_str()) == 0 ? out : "";
}

TEST(Urdf, PassesCheckUrdfAndIsWhatItsGeneratorWrites) {
  const std::string dir = F3R_SOURCE_DIR;
  EXPECT_EQ(std::system(("check_urdf " + dir + "/urdf/flex3rpr.urdf > /dev/null").c_str()), 0);
  const std::string fresh = Generate("", "/tmp/f3r_urdf_check.urdf");
  ASSERT_FALSE(fresh.empty());
  EXPECT_EQ(std::system(("cmp -s " + fresh + " " + dir + "/urdf/flex3rpr.urdf").c_str()), 0)
      << "urdf/flex3rpr.urdf is out of date: run nodes/make_urdf.py --out urdf/flex3rpr.urdf";
}

// A generated URDF for other stations, a prefix and another scene: valid, names unique, every
// link below a moving joint has an inertial, its mass is the model's, and it passes the node's
// own check for those frames.
TEST(Urdf, GeneratedForAnySettingIsCompleteAndMatchesTheModel) {
  const std::string scene = std::string(F3R_SOURCE_DIR) + "/config/scenes/end_stop_impact.yaml";
  const std::string path =
      Generate("--scene " + scene + " --beam-points 5 --prefix robot2", "/tmp/f3r_urdf_5.urdf");
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(std::system(("check_urdf " + path + " > /dev/null").c_str()), 0);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  urdf::ModelInterfaceSharedPtr u = urdf::parseURDF(ss.str());
  ASSERT_TRUE(u);
  std::set<std::string> names;
  for (const auto& l : u->links_) EXPECT_TRUE(names.insert(l.first).second) << l.first;
  for (const auto& j : u->joints_)
    EXPECT_TRUE(names.insert(j.first).second) << j.first << " is a link too";
  double mass = 0.0;
  for (const auto& j : u->joints_) {
    const auto child = u->getLink(j.second->child_link_name);
    ASSERT_TRUE(child);
    if (j.second->type != urdf::Joint::FIXED) {
      EXPECT_TRUE(child->inertial && child->inertial->mass > 0.0)
          << child->name << " moves but has no inertial";
    }
  }
  for (const auto& l : u->links_)
    if (l.second->inertial) mass += l.second->inertial->mass;
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load(scene.c_str(), &s, &err), F3R_OK) << err.message;
  f3r_model* m = nullptr;
  ASSERT_EQ(f3r_model_create(&s, &m, &err), F3R_OK);
  const f3r_geometry g = f3r_model_geometry(m);
  EXPECT_NEAR(mass, g.platform_mass + 3 * (g.link_mass + g.cylinder_mass), 1e-12);
  const flex3rpr::FrameNames frames =
      flex3rpr::MakeFrameNames("robot2/", "world", "robot2/base", 5);
  EXPECT_EQ(flex3rpr::CheckUrdf(ss.str(), *m, &frames), "");
  EXPECT_EQ(u->getJoint("leg_2_prismatic")->limits->upper, g.stroke_max);
  f3r_model_destroy(m);
  f3r_scene_free(&s);
}

TEST(Pacer, KeepsTheRequestedScheduleWhenOnTime) {
  flex3rpr::Pacer p(2.0);  // 2 simulated s per wall s
  p.Start(100.0, 0.0);
  EXPECT_DOUBLE_EQ(p.Due(100.001, 0.01), 100.005);  // early: sleep until its time
  EXPECT_DOUBLE_EQ(p.Due(100.030, 0.02), 100.010);  // 20 ms late: catch up (jitter)
  EXPECT_EQ(p.resyncs(), 0u);
  EXPECT_NEAR(p.lag(), 0.020, 1e-12);
}

TEST(Pacer, AfterAStallStartsAgainFromThePresentInsteadOfRacing) {
  flex3rpr::Pacer p(1.0);
  p.Start(0.0, 0.0);
  for (int k = 1; k <= 100; ++k) p.Due(0.001 * k, 0.001 * k);  // on time for 0.1 s
  // Stopped for 3 s: the next period ends at wall 3.101. A pacer that raced would want the next
  // 3 s of simulation as fast as it can (its due time 0.102 lies in the past).
  EXPECT_DOUBLE_EQ(p.Due(3.101, 0.101), 3.101);
  EXPECT_EQ(p.resyncs(), 1u);
  EXPECT_NEAR(p.Due(3.1015, 0.102), 3.102, 1e-12);  // paced again, one period after the stall
  EXPECT_EQ(p.resyncs(), 1u);
}

TEST(Pacer, SaysBehindBelowNinetyFivePercentOfTheRequest) {
  flex3rpr::Pacer p(1.0);
  p.Start(0.0, 0.0);
  double wall = 0.0, sim = 0.0;
  // (a window may take one step of its neighbour: rounding of the summed wall time)
  for (int k = 0; k < 100; ++k) p.Due(wall += 0.01, sim += 0.0096);  // 0.96 of real time
  EXPECT_FALSE(p.behind());
  EXPECT_NEAR(p.achieved(), 0.96, 1e-3);
  for (int k = 0; k < 100; ++k) p.Due(wall += 0.01, sim += 0.0094);  // 0.94
  EXPECT_TRUE(p.behind());
  EXPECT_NEAR(p.achieved(), 0.94, 1e-3);
  flex3rpr::Pacer unpaced(0.0);  // as fast as it can: never behind, never sleeps
  unpaced.Start(0.0, 0.0);
  for (int k = 1; k < 60; ++k) EXPECT_EQ(unpaced.Due(0.01 * k, 0.0001 * k), 0.01 * k);
  EXPECT_FALSE(unpaced.behind());
}

}  // namespace
