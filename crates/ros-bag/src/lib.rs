//! ROS 2 bags stored as MCAP (work in progress).
