//! The terrain engine's fly camera ([`terrain::camera::FlyCamera`], y-up) flying the ray
//! tracer's camera (z-up). The two worlds are turned into each other by a rotation: the ray
//! tracer's `(x, y, z)` is the terrain's `(x, z, -y)`, so the terrain's yaw 0 looks along the
//! ray tracer's `+y` and its pitch is the angle above the ray tracer's horizon.

use glam::{DVec3, Vec3};
use terrain::camera::{CameraPose, FlyCamera, MotionSettings};

use super::pose::Pose;

/// A point or direction of the ray tracer's world in the terrain's.
fn to_terrain(v: DVec3) -> Vec3 {
    Vec3::new(v.x as f32, v.z as f32, -v.y as f32)
}

/// A point or direction of the terrain's world in the ray tracer's.
fn from_terrain(v: Vec3) -> DVec3 {
    DVec3::new(f64::from(v.x), -f64::from(v.z), f64::from(v.y))
}

/// The fly camera at `pose`, moving at most `speed` scene units a second (4 times that with
/// Shift). A view straight up or down is tilted to the fly camera's 89 degrees.
pub fn fly_camera(pose: &Pose, speed: f32) -> FlyCamera {
    let forward = to_terrain(pose.dir);
    let yaw = forward.x.atan2(-forward.z).to_degrees();
    let pitch = forward.y.clamp(-1.0, 1.0).asin().to_degrees();
    let settings = MotionSettings { max_speed: speed, ..MotionSettings::default() };
    FlyCamera::new(CameraPose::new(to_terrain(pose.eye), yaw.rem_euclid(360.0), pitch), 60.0, settings)
}

/// The ray tracer's pose of the fly camera.
pub fn pose_of(camera: &FlyCamera) -> Pose {
    let pose = camera.pose();
    Pose { eye: from_terrain(pose.position), dir: from_terrain(pose.forward()).normalize() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use terrain::camera::{Limits, Motion};

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn a_pose_goes_through_the_fly_camera_unchanged() {
        for dir in [DVec3::Y, DVec3::X, DVec3::new(0.6, 1.0, -0.6), DVec3::new(-1.0, -2.0, 0.3)] {
            let pose = Pose { eye: DVec3::new(-2.0, 2.0, 0.5), dir: dir.normalize() };
            let back = pose_of(&fly_camera(&pose, 1.0));
            assert!(close(back.eye, pose.eye) && close(back.dir, pose.dir), "{pose:?} came back as {back:?}");
        }
    }

    #[test]
    fn keys_move_along_the_view_and_up_is_z() {
        let pose = Pose { eye: DVec3::ZERO, dir: DVec3::Y };
        let step = |motion: Motion| {
            let mut camera = fly_camera(&pose, 1.0);
            camera.set_held(motion, true);
            camera.update(10.0, &Limits::NONE, |_, _| None);
            let moved = pose_of(&camera).eye;
            moved / moved.length()
        };
        assert!(close(step(Motion::Forward), DVec3::Y));
        assert!(close(step(Motion::Up), DVec3::Z));
        // The course's right vector is `N x z`: +x when looking along +y.
        assert!(close(step(Motion::Right), DVec3::X));
    }
}
