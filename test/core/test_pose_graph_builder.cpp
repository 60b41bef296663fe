// PoseGraphBuilder: keyframes from odometry, loops anchored by stamp, the adjoint, and a drifted loop
// corrected — known answers, no ROS.
#include <gtest/gtest.h>

#include <cmath>

#include "openable/pose_graph/pose_graph_builder.h"

using openable::LoopMeasurement;
using openable::Matrix6d;
using openable::PoseGraphBuilder;

namespace
{
Eigen::Isometry3d at(double x, double y, double yaw)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, 0.0);
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

Eigen::Matrix4d hat(const Eigen::Matrix<double, 6, 1>& e)
{
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m.block<3, 3>(0, 0) << 0, -e(5), e(4), e(5), 0, -e(3), -e(4), e(3), 0;
  m.block<3, 1>(0, 3) = e.head<3>();
  return m;
}
}  // namespace

TEST(PoseGraphBuilder, KeyframesEveryMetreAndLateOrRestartedOdometry)
{
  PoseGraphBuilder builder;  // 1 m / 0.2 rad
  int keyframes = 0;
  for (int i = 0; i < 20; ++i)
    keyframes += builder.addOdometry(1.0 + i, at(0.3 * i, 0, 0)) == PoseGraphBuilder::Odometry::Keyframe;
  EXPECT_EQ(keyframes, 5);  // at 0, 1.2, 2.4, 3.6 and 4.8 m
  EXPECT_EQ(builder.keyframes(), 5u);
  EXPECT_DOUBLE_EQ(builder.keyframeStamp(1), 5.0);
  EXPECT_EQ(builder.addOdometry(10.5, at(2.9, 0, 0)), PoseGraphBuilder::Odometry::Late);
  EXPECT_EQ(builder.keyframes(), 5u);
  EXPECT_EQ(builder.addOdometry(0.5, at(0, 0, 0)), PoseGraphBuilder::Odometry::Restarted);
  EXPECT_EQ(builder.keyframes(), 1u);
}

TEST(PoseGraphBuilder, LoopsAreAnchoredToTheNearestKeyframeOrWaitOrAreRefused)
{
  PoseGraphBuilder builder;
  for (int i = 0; i <= 40; ++i)
    builder.addOdometry(1.0 + 0.1 * i, at(0.1 * i, 0, 0));  // 1 m every 10 samples: keyframes at 1, 2, 3, 4, 5 s
  LoopMeasurement loop;
  loop.query_stamp = 4.96;  // nearest keyframe: 5.0 s (node 4)
  loop.match_stamp = 1.04;  // nearest: 1.0 s (node 0)
  EXPECT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::Added);
  ASSERT_EQ(builder.loops().size(), 1u);
  EXPECT_EQ(builder.loops()[0], std::make_pair(size_t(0), size_t(4)));
  EXPECT_TRUE(builder.dirty());

  loop.query_stamp = 6.0;  // newer than the odometry
  EXPECT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::Wait);
  loop.query_stamp = 0.5;  // older than the odometry
  EXPECT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::Unplaced);
  loop.query_stamp = 1.02;
  EXPECT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::SameKeyframe);
  loop.query_stamp = 4.0;
  loop.has_relative_pose = true;  // a covariance of zeros cannot be inverted: default sigmas
  EXPECT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::AddedWithDefaultCovariance);
}

TEST(PoseGraphBuilder, AdjointMovesPerturbationsBetweenFrames)
{
  // hat(Ad_T e) = T hat(e) T^-1 for every e (the defining property).
  Eigen::Isometry3d t = at(1.0, -2.0, 0.7);
  t.translation().z() = 0.5;
  const Matrix6d ad = PoseGraphBuilder::adjoint(t);
  for (int k = 0; k < 6; ++k)
  {
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    e(k) = 1.0;
    const Eigen::Matrix4d expected = t.matrix() * hat(e) * t.inverse().matrix();
    EXPECT_TRUE(hat(ad * e).isApprox(expected, 1e-12)) << "axis " << k;
  }
}

TEST(PoseGraphBuilder, InterpolatesBetweenOdometrySamples)
{
  const Eigen::Isometry3d half = PoseGraphBuilder::interpolate(at(0, 0, 0), at(2, 0, 1.0), 0.5);
  EXPECT_NEAR(half.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(half.rotation()).angle(), 0.5, 1e-12);
}

TEST(PoseGraphBuilder, AVerifiedLoopPullsADriftedSquareClosed)
{
  openable::PoseGraphBuilderOptions options;
  options.graph.loop_loss = openable::RobustLoss::None;
  PoseGraphBuilder builder(options);
  // A 10 m square driven once; odometry under-reports every turn by 0.02 rad, so the end drifts away.
  Eigen::Isometry3d odom = Eigen::Isometry3d::Identity();
  double stamp = 1.0;
  builder.addOdometry(stamp, odom);
  for (int side = 0; side < 4; ++side)
  {
    for (int step = 0; step < 20; ++step)
    {
      odom = odom * at(0.5, 0, 0);
      builder.addOdometry(stamp += 0.1, odom);
    }
    odom = odom * at(0, 0, M_PI / 2 - 0.02);
    builder.addOdometry(stamp += 0.1, odom);
  }
  const double drift_before = builder.graph().pose(builder.keyframes() - 1).translation().norm();
  EXPECT_GT(drift_before, 0.3);
  LoopMeasurement loop;
  loop.query_stamp = stamp;
  loop.match_stamp = 1.0;
  loop.has_relative_pose = true;  // the cameras coincide: back at the start
  loop.covariance = Matrix6d::Identity() * 1e-4;
  ASSERT_EQ(builder.addLoop(loop), PoseGraphBuilder::Loop::Added);
  ASSERT_TRUE(builder.optimize().usable);
  EXPECT_FALSE(builder.dirty());
  const double drift_after = builder.graph().pose(builder.keyframes() - 1).translation().norm();
  EXPECT_LT(drift_after, 0.1 * drift_before);
  EXPECT_LT(builder.mapFromOdometry().translation().norm() + 1e-9, 10.0);
}
