#include "openable_ros/pose_lookup.h"

#include <geometry_msgs/TransformStamped.h>
#include <tf2/exceptions.h>

#include <sstream>

namespace openable_ros
{
PoseLookup::PoseLookup(ros::NodeHandle& nh, const std::string& fixed_frame, double timeout)
  : fixed_frame_(fixed_frame), timeout_(timeout)
{
  if (fixed_frame_.empty())
    return;
  buffer_ = std::make_unique<tf2_ros::Buffer>();
  listener_ = std::make_unique<tf2_ros::TransformListener>(*buffer_, nh);
}

bool PoseLookup::lookup(const std_msgs::Header& header, std::array<double, 7>& pose, std::string& problem) const
{
  if (!buffer_)
    return false;
  if (header.frame_id.empty())
  {
    problem = "the input's header.frame_id is empty: no camera pose in '" + fixed_frame_ +
              "' can be looked up; frames are kept without pose";
    return false;
  }
  try
  {
    const geometry_msgs::TransformStamped t =
        buffer_->lookupTransform(fixed_frame_, header.frame_id, header.stamp, ros::Duration(timeout_));
    pose = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z, t.transform.rotation.x,
            t.transform.rotation.y,    t.transform.rotation.z,    t.transform.rotation.w};
    return true;
  }
  catch (const tf2::TransformException& e)
  {
    std::ostringstream what;
    what << "no transform '" << fixed_frame_ << "' <- '" << header.frame_id << "' at " << header.stamp
         << " within ~tf_timeout " << timeout_ << " s (" << e.what() << "); frame kept without pose";
    problem = what.str();
    return false;
  }
}

void PoseLookup::clear()
{
  if (buffer_)
    buffer_->clear();
}

}  // namespace openable_ros
