// Checker for multi-robot loop closure (place_server_robots.test, place_server_split.test): two robots'
// mono detectors in their own namespaces get Gardens Point day_left (robot1) and night_right (robot2)
// frames, alternating, and publish place_descriptors; PlaceServers close loops between them. Image NNN is
// the same place in both traversals, so a loop closure is right when the match is within 2 frames.
//
// Frame by frame: the next image goes out only after every watched `decisions` topic has decided the last
// one, so the servers see the robots' frames in the order of the core test (test_place_server.cpp) and
// the outcome is reproducible. ~loop_topics[0] is asserted against the measured precision and recall; every
// further topic must publish exactly the same loop closures (split servers + merger vs one server).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <openable_ros/PlaceDescriptor.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include <fstream>
#include <mutex>
#include <sstream>

#include "test_helpers.h"

using openable_ros_test::waitFor;

namespace
{
/// Every message of one LoopClosure topic.
class Topic
{
public:
  Topic(ros::NodeHandle& nh, const std::string& name)
  {
    sub_ = nh.subscribe<openable_ros::LoopClosure>(name, 1000, [this](const openable_ros::LoopClosureConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      messages_.push_back(m);
    });
  }
  std::vector<openable_ros::LoopClosureConstPtr> messages()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  bool has(const std::string& session, uint32_t id)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = messages_.rbegin(); it != messages_.rend(); ++it)
      if ((*it)->query_session_name == session && (*it)->query_id == id)
        return true;
    return false;
  }
  ros::Subscriber sub_;

private:
  std::mutex mutex_;
  std::vector<openable_ros::LoopClosureConstPtr> messages_;
};

/// One loop closure in words, to compare topics.
std::string text(const openable_ros::LoopClosure& m)
{
  std::ostringstream out;
  out << m.query_session_name << "#" << m.query_id << " -> " << m.match_session_name << "#" << m.match_id << " d "
      << m.distance << " u " << m.uniqueness;
  return out.str();
}

/// The connections of `node` (XML-RPC getBusInfo): one line per connection, "topic info".
std::vector<std::string> busInfo(const std::string& node)
{
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  request[1] = node;
  std::vector<std::string> out;
  if (!ros::master::execute("lookupNode", request, response, payload, false))
    return out;
  const std::string uri = payload;
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(uri, host, port))
    return out;
  XmlRpc::XmlRpcClient client(host.c_str(), int(port), "/");
  XmlRpc::XmlRpcValue args, result;
  args[0] = ros::this_node::getName();
  if (!client.execute("getBusInfo", args, result) || result.size() < 3)
    return out;
  XmlRpc::XmlRpcValue& connections = result[2];
  for (int i = 0; i < connections.size(); ++i)
  {
    XmlRpc::XmlRpcValue& c = connections[i];
    // [id, destination, direction, transport, topic, connected, info]
    const bool connected = c.size() > 5 && c[5].getType() == XmlRpc::XmlRpcValue::TypeBoolean && bool(c[5]);
    std::string info = c.size() > 6 ? std::string(c[6]) : "";
    if (connected || c.size() <= 5)
      out.push_back(std::string(c[4]) + " " + info);
  }
  return out;
}

/// True when a TCP connection to `address`:`port` is established on this machine (/proc/net/tcp): a
/// node's bus lists a link it is still retrying too, so the kernel has the last word.
bool established(const std::string& address, int port)
{
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (std::sscanf(address.c_str(), "%u.%u.%u.%u", &a, &b, &c, &d) != 4)
    return false;
  char endpoint[32];
  std::snprintf(endpoint, sizeof(endpoint), "%02X%02X%02X%02X:%04X", d, c, b, a, unsigned(port));
  std::ifstream tcp("/proc/net/tcp");
  std::string line;
  while (std::getline(tcp, line))
  {
    std::istringstream words(line);
    std::string slot, local, remote, state;
    words >> slot >> local >> remote >> state;
    if (remote == endpoint && state == "01")
      return true;
  }
  return false;
}

/// Connections of `node` on `topic`; with an address, only those established to that host (the ROS_IP /
/// ROS_HOSTNAME the publishing node advertises), from the link's info "... to [host:port on socket n]".
size_t connections(const std::string& node, const std::string& topic, const std::string& address = "")
{
  size_t n = 0;
  for (const std::string& line : busInfo(node))
  {
    if (line.compare(0, topic.size() + 1, topic + " ") != 0)
      continue;
    const size_t at = line.find("to [" + address + ":");
    if (address.empty())
      ++n;
    else if (at != std::string::npos)
      n += established(address, std::atoi(line.c_str() + at + 5 + address.size()));
  }
  return n;
}

/// The last value of `key` in the "place server" diagnostic status of `node`.
class ServerDiagnostics
{
public:
  explicit ServerDiagnostics(ros::NodeHandle& nh)
  {
    sub_ = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArrayConstPtr& msg) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const auto& s : msg->status)
            if (s.name.find("place server") != std::string::npos)
              for (const auto& kv : s.values)
                values_[kv.key] = kv.value;
        });
  }
  long number(const std::string& key)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = values_.find(key);
    return it == values_.end() ? -1 : std::stol(it->second);
  }

private:
  ros::Subscriber sub_;
  std::mutex mutex_;
  std::map<std::string, std::string> values_;
};

std::vector<std::string> listParam(ros::NodeHandle& pnh, const std::string& name)
{
  std::vector<std::string> v;
  pnh.getParam(name, v);
  return v;
}
}  // namespace

TEST(PlaceServer, TwoRobotsCloseLoopsBetweenThemThroughPlaceServers)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string data = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  const std::vector<std::string> decision_topics = listParam(pnh, "decision_topics");
  const std::vector<std::string> loop_topics = listParam(pnh, "loop_topics");
  // "node topic count [address]": connections that must exist before the first frame (and, with an
  // address, come from that host: the ROS_IP of the publishing node).
  const std::vector<std::string> wanted = listParam(pnh, "connections");
  ASSERT_FALSE(loop_topics.empty());
  ASSERT_EQ(decision_topics.size(), loop_topics.size());

  std::vector<cv::Mat> day, night;
  char name[32];
  for (int i = 0; i < 200; ++i)
  {
    std::snprintf(name, sizeof(name), "/Image%03d.jpg", i);
    day.push_back(cv::imread(data + "/day_left" + name, cv::IMREAD_COLOR));
    night.push_back(cv::imread(data + "/night_right" + name, cv::IMREAD_COLOR));
    ASSERT_FALSE(day.back().empty() || night.back().empty()) << data << name;
  }

  std::vector<std::unique_ptr<Topic>> decisions, loops;
  for (size_t t = 0; t < loop_topics.size(); ++t)
  {
    decisions.push_back(std::make_unique<Topic>(nh, decision_topics[t]));
    loops.push_back(std::make_unique<Topic>(nh, loop_topics[t]));
  }
  ros::Publisher image1 = nh.advertise<sensor_msgs::Image>("/robot1/image", 10);
  ros::Publisher image2 = nh.advertise<sensor_msgs::Image>("/robot2/image", 10);
  ros::AsyncSpinner spinner(2);
  spinner.start();

  // Everything connected before the first frame (a frame a server misses is a gap in its sequences).
  for (const std::string& line : wanted)
  {
    std::istringstream words(line);
    std::string node, topic, address;
    size_t count = 0;
    words >> node >> topic >> count >> address;
    EXPECT_TRUE(waitFor([&] { return connections(node, topic, address) >= count; }, 30.0))
        << node << " has " << connections(node, topic, address) << " connections on " << topic << " from '" << address
        << "', expected " << count << "; its bus: " << ::testing::PrintToString(busInfo(node));
  }
  EXPECT_TRUE(waitFor([&] { return image1.getNumSubscribers() > 0 && image2.getNumSubscribers() > 0; }, 30.0));
  for (size_t t = 0; t < loop_topics.size(); ++t)
    ASSERT_TRUE(waitFor([&] { return decisions[t]->sub_.getNumPublishers() > 0; }, 30.0)) << decision_topics[t];

  // Frame by frame, robot1 then robot2, each decided on every topic before the next goes out.
  const ros::Time start(1000.0);
  for (uint32_t i = 0; i < 200; ++i)
  {
    const std::vector<std::pair<ros::Publisher*, const cv::Mat*>> frames = {{&image1, &day[i]}, {&image2, &night[i]}};
    for (size_t r = 0; r < 2; ++r)
    {
      const std::string session = r == 0 ? "robot1" : "robot2";
      frames[r].first->publish(
          openable_ros_test::toMsg(*frames[r].second, "bgr8", start + ros::Duration(i + 0.25 * double(r))));
      for (size_t t = 0; t < decisions.size(); ++t)
        ASSERT_TRUE(waitFor([&] { return decisions[t]->has(session, i); }, 10.0))
            << decision_topics[t] << " never decided " << session << " frame " << i;
    }
  }

  // Loop closures are published before the decision that follows them: they are all here.
  const auto published = loops[0]->messages();
  size_t right = 0;
  for (const auto& m : published)
  {
    EXPECT_NE(m->query_session_name, m->match_session_name) << "a robot never walks its own route twice";
    EXPECT_NE(m->query_session, m->match_session);
    right += std::labs(long(m->match_id) - long(m->query_id)) <= 2;
  }
  const double precision = published.empty() ? 0.0 : double(right) / double(published.size());
  const double recall = double(right) / 400.0;
  RecordProperty("published", int(published.size()));
  RecordProperty("precision", std::to_string(precision));
  RecordProperty("recall", std::to_string(recall));
  std::printf("%s: %zu inter-robot loop closures, precision %.3f, recall %.4f\n", loop_topics[0].c_str(),
              published.size(), precision, recall);
  EXPECT_GE(precision, pnh.param("min_precision", 1.0));
  EXPECT_GE(recall, pnh.param("min_recall", 0.04));

  // Every further topic (split servers + merger) publishes exactly the same loop closures.
  for (size_t t = 1; t < loops.size(); ++t)
  {
    std::vector<std::string> a, b;
    for (const auto& m : published)
      a.push_back(text(*m));
    for (const auto& m : loops[t]->messages())
      b.push_back(text(*m));
    EXPECT_EQ(b, a) << loop_topics[t] << " vs " << loop_topics[0];
  }

  // A descriptor of another configuration is refused, counted in the diagnostics and nothing is stored.
  const std::string refused_server = pnh.param<std::string>("refusal_diagnostics", "");
  if (!refused_server.empty())
  {
    ServerDiagnostics diagnostics(nh);
    ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames in map") >= 0; }, 10.0));
    const long frames = diagnostics.number("frames in map");
    ros::Publisher bad = nh.advertise<openable_ros::PlaceDescriptor>("/robot1/place_descriptors", 10);
    openable_ros::PlaceDescriptor msg;
    msg.header.stamp = start + ros::Duration(500.0);
    msg.robot = "robot1";
    msg.session = "robot1";
    msg.config_hash = 42;
    msg.descriptor.assign(6, 0);
    EXPECT_TRUE(waitFor(
        [&] {
          bad.publish(msg);
          ros::WallDuration(0.05).sleep();
          return diagnostics.number("refused: configuration hash") >= 1;
        },
        20.0));
    EXPECT_EQ(diagnostics.number("frames in map"), frames);
  }
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_place_server");
  return RUN_ALL_TESTS();
}
