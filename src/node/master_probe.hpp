// Which subscribers the ROS master lists are still there: a process that was killed leaves its
// registrations behind, and its XML-RPC port refuses. ~wait_for_subscribers counts only those.
#pragma once

#include <map>
#include <string>

namespace flex3rpr {

// Per topic, the subscribers registered with the master whose node still accepts a connection
// at its XML-RPC URI (each node asked once, within a wall second). Empty when the master does
// not answer.
std::map<std::string, int> AnsweringSubscribers();

}  // namespace flex3rpr
