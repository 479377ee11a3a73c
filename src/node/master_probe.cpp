// The master's view of the subscribers, checked against the processes behind it
// (master_probe.hpp): raw TCP, apart from the node's outputs.
#include "master_probe.hpp"

#include <netdb.h>
#include <poll.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/this_node.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>

namespace flex3rpr {

namespace {

// True when a TCP connection to host:port is accepted within a wall second.
bool Accepts(const std::string& host, uint32_t port) {
  addrinfo hints{}, *found = nullptr;
  hints.ai_socktype = SOCK_STREAM;
  if (getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0) return false;
  bool accepted = false;
  for (addrinfo* a = found; a && !accepted; a = a->ai_next) {
    const int fd = socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int error = connect(fd, a->ai_addr, a->ai_addrlen) == 0 ? 0 : errno;
    if (error == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      socklen_t size = sizeof error;
      error = poll(&p, 1, 1000) == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &size) == 0
                  ? error
                  : ETIMEDOUT;
    }
    accepted = error == 0;
    ::close(fd);
  }
  freeaddrinfo(found);
  return accepted;
}

// True when the node the master lists under name still listens at its XML-RPC URI: a process
// that was killed leaves its registrations behind, and its port refuses.
bool NodeAnswers(const std::string& name) {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  request[1] = name;
  if (!ros::master::execute("lookupNode", request, response, payload, false)) return false;
  std::string host;
  uint32_t port = 0;
  return ros::network::splitURI(static_cast<std::string>(payload), host, port) &&
         Accepts(host, port);
}

}  // namespace

std::map<std::string, int> AnsweringSubscribers() {
  // getSystemState: [publishers, subscribers, services], each [topic, [node, ...]]
  std::map<std::string, int> registered;
  std::map<std::string, bool> answers;  // per node, asked once per call
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (ros::master::execute("getSystemState", request, response, payload, false) &&
      payload.size() > 1) {
    for (int i = 0; i < payload[1].size(); ++i) {
      int& count = registered[static_cast<std::string>(payload[1][i][0])];
      for (int k = 0; k < payload[1][i][1].size(); ++k) {
        const std::string name = payload[1][i][1][k];
        if (!answers.count(name)) answers[name] = NodeAnswers(name);
        count += answers[name] ? 1 : 0;
      }
    }
  }
  return registered;
}

}  // namespace flex3rpr
