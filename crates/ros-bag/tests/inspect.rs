//! The inspection of a bag: per topic its type, encoding, count, rate, times and fields.

mod common;

use common::fixture;
use ros_bag::Bag;

#[test]
fn the_ros2_fixture_table() {
    let i = Bag::open(fixture("ros2_zstd.mcap")).unwrap().inspect();
    assert!(i.error.is_none());
    let names: Vec<&str> = i.topics.iter().map(|t| t.topic.as_str()).collect();
    assert_eq!(names, ["/cmd_vel", "/gnss/fix", "/imu", "/odom"]);
    let imu = &i.topics[2];
    assert_eq!(
        (imu.message_type.as_str(), imu.message_encoding.as_str(), imu.schema_encoding.as_str()),
        ("sensor_msgs/msg/Imu", "cdr", "ros2msg")
    );
    assert_eq!(imu.count, 300);
    let rate = imu.rate_hz().unwrap();
    assert!((99.0..101.0).contains(&rate), "{rate}");
    for f in ["angular_velocity.z", "orientation_covariance[0..=8]", "header.stamp.nanosec"] {
        assert!(imu.numeric_fields.iter().any(|x| x == f), "{f}: {:?}", imu.numeric_fields);
    }
    let gnss = &i.topics[1];
    assert_eq!(gnss.count, 20, "30 fixes less the second of dropout");
    assert!(gnss.numeric_fields.iter().any(|x| x == "status.status"));
    let text = i.to_string();
    let first = text.lines().next().unwrap();
    assert!(first.starts_with("topic") && first.contains("rate (Hz)"), "{first}");
    assert!(text.contains("sensor_msgs/msg/NavSatFix") && text.contains("cdr/ros2msg"), "{text}");
    assert!(text.contains("    fields: header.stamp.sec, header.stamp.nanosec, orientation.x"), "{text}");
    println!("{text}");
}

#[test]
fn json_topics_list_the_schema_fields_or_none() {
    let i = Bag::open(fixture("json.mcap")).unwrap().inspect();
    let pose = i.topics.iter().find(|t| t.topic == "/pose_json").unwrap();
    assert_eq!(pose.numeric_fields, ["header.stamp.nanosec", "header.stamp.sec", "valid", "x"]);
    let speed = i.topics.iter().find(|t| t.topic == "/speed_json").unwrap();
    assert!(speed.numeric_fields.is_empty() && speed.fields_error.is_none());
    assert_eq!(speed.count, 50);
    assert!(i.to_string().contains("json/-"));
}
