//! The terrain engine's fly camera ([`terrain::camera::FlyCamera`], y-up) flying the ray
//! tracer's camera (z-up). The two worlds are turned into each other by a rotation: the ray
//! tracer's `(x, y, z)` is the terrain's `(x, z, -y)`, so the terrain's yaw 0 looks along the
//! ray tracer's `+y` and its pitch is the angle above the ray tracer's horizon.

use glam::{DVec3, Vec3};
use terrain::camera::{CameraPose, FlyCamera, MotionSettings};

use super::pose::Pose;

/// The scene's axes that become the terrain's `x`, `y` (up) and `z` for a world whose up is
/// `up`: for `+z`, `(x, z, -y)` as above; for another up (a y-up Mitsuba scene), the same
/// turned so that `up` is the terrain's `+y`.
fn axes(up: DVec3) -> [DVec3; 3] {
    let up = up.try_normalize().unwrap_or(DVec3::Z);
    let a = (DVec3::X - up * up.x).try_normalize().unwrap_or_else(|| (DVec3::Y - up * up.y).normalize());
    [a, up, a.cross(up)]
}

/// A point or direction of the scene's world (whose up is `up`) in the terrain's.
fn to_terrain(v: DVec3, up: DVec3) -> Vec3 {
    let [a, b, c] = axes(up);
    Vec3::new(v.dot(a) as f32, v.dot(b) as f32, v.dot(c) as f32)
}

/// A point or direction of the terrain's world in the scene's (whose up is `up`).
fn from_terrain(v: Vec3, up: DVec3) -> DVec3 {
    let [a, b, c] = axes(up);
    a * f64::from(v.x) + b * f64::from(v.y) + c * f64::from(v.z)
}

/// The fly camera at `pose`, moving at most `speed` scene units a second (4 times that with
/// Shift). A view straight up or down is tilted to the fly camera's 89 degrees.
pub fn fly_camera(pose: &Pose, speed: f32) -> FlyCamera {
    let forward = to_terrain(pose.dir, pose.up);
    let yaw = forward.x.atan2(-forward.z).to_degrees();
    let pitch = forward.y.clamp(-1.0, 1.0).asin().to_degrees();
    let settings = MotionSettings { max_speed: speed, ..MotionSettings::default() };
    FlyCamera::new(
        CameraPose::new(to_terrain(pose.eye, pose.up), yaw.rem_euclid(360.0), pitch),
        60.0,
        settings,
    )
}

/// The scene's pose of the fly camera, in a world whose up is `up`.
pub fn pose_of(camera: &FlyCamera, up: DVec3) -> Pose {
    let pose = camera.pose();
    Pose { eye: from_terrain(pose.position, up), dir: from_terrain(pose.forward(), up).normalize(), up }
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
            let pose = Pose { eye: DVec3::new(-2.0, 2.0, 0.5), dir: dir.normalize(), up: DVec3::Z };
            let back = pose_of(&fly_camera(&pose, 1.0), pose.up);
            assert!(close(back.eye, pose.eye) && close(back.dir, pose.dir), "{pose:?} came back as {back:?}");
        }
    }

    #[test]
    fn keys_move_along_the_view_and_up_is_z() {
        let pose = Pose { eye: DVec3::ZERO, dir: DVec3::Y, up: DVec3::Z };
        let step = |motion: Motion| {
            let mut camera = fly_camera(&pose, 1.0);
            camera.set_held(motion, true);
            camera.update(10.0, &Limits::NONE, |_, _| None);
            let moved = pose_of(&camera, pose.up).eye;
            moved / moved.length()
        };
        assert!(close(step(Motion::Forward), DVec3::Y));
        assert!(close(step(Motion::Up), DVec3::Z));
        // The course's right vector is `N x z`: +x when looking along +y.
        assert!(close(step(Motion::Right), DVec3::X));
    }

    #[test]
    fn a_y_up_world_flies_with_y_up() {
        // A Mitsuba scene's camera looking along +z with +y up.
        let pose = Pose { eye: DVec3::new(1.0, 2.0, 3.0), dir: DVec3::Z, up: DVec3::Y };
        let back = pose_of(&fly_camera(&pose, 1.0), pose.up);
        assert!(close(back.eye, pose.eye) && close(back.dir, pose.dir), "{back:?}");
        let mut camera = fly_camera(&pose, 1.0);
        camera.set_held(Motion::Up, true);
        camera.update(10.0, &Limits::NONE, |_, _| None);
        let moved = pose_of(&camera, pose.up).eye - pose.eye;
        assert!(close(moved / moved.length(), DVec3::Y), "up is the scene's up: {moved:?}");
    }
}
