//! The same scene and settings give the same image bit for bit, whatever the thread count.

mod support;

use support::{load, render, workspace};

#[test]
fn adaptive_render_does_not_depend_on_threads() {
    let scene = load(&workspace().join("scenes/showcase.txt"));
    let one = render(&scene, 96, 57, None, Some(1));
    let three = render(&scene, 96, 57, None, Some(3));
    assert!(one == three, "1 and 3 threads rendered different images");
    let again = render(&scene, 96, 57, None, Some(2));
    assert!(one == again, "a second render differs");
}

#[test]
fn uniform_sampling_does_not_depend_on_threads() {
    let scene = load(&workspace().join("scenes/cornell.txt"));
    let one = render(&scene, 48, 48, Some(4), Some(1));
    let four = render(&scene, 48, 48, Some(4), Some(4));
    assert!(one == four, "1 and 4 threads rendered different images");
}
