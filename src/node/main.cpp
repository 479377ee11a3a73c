// flex3rpr_node: the simulator as a ROS node. All physics is in the C core; see sim_node.cpp.
#include <ros/ros.h>

#include "sim_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "flex3rpr_node");
  flex3rpr::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"));
  if (!node.Init()) return 1;
  return node.Run();
}
