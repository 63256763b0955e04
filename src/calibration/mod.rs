//! Calibration (feature `calibration`): what a real camera and robot must be measured for
//! before the servo loop runs on them.
//!
//! | concept | module |
//! |---|---|
//! | camera calibration files: ROS `camera_info` YAML, OpenCV `FileStorage` YAML and XML | [`camera_file`] |
//! | hand-eye calibration: the camera's mount on the flange, or its place beside the robot, from robot and target poses (AX = XB) | [`hand_eye`] |
//!
//! The names of both are re-exported here (`vsinv::calibration::load_calibration`,
//! `vsinv::calibration::calibrate_hand_eye`).

pub mod camera_file;
pub mod error;
pub mod hand_eye;

pub use camera_file::{
    Calibration, MAX_CALIBRATION_BYTES, MAX_DISTORTION_COEFFICIENT, MAX_INTRINSIC_PIXELS, MAX_XML_NODES,
    load_calibration, parse_calibration,
};
pub use error::CalibrationError;
pub use hand_eye::{
    AxisSpread, HandEyeAgreement, HandEyeCalibration, HandEyeMethod, HandEyeSetup, PairResidual, calibrate_hand_eye,
    compare_hand_eye_methods,
};
