//! The Embree 4 library from the `embreex` wheel links and answers: a ray hits a round linear
//! curve at the distance geometry predicts.
use coif::embree::{Device, Scene};
use glam::Vec3;

#[test]
fn ray_hits_a_round_curve_at_the_predicted_distance() {
    let device = Device::new().unwrap();
    let mut scene = Scene::new(&device).unwrap();
    // A tube of radius 0.1 along X through the origin.
    let id = scene.add_round_linear_curves(&[[-1.0, 0.0, 0.0, 0.1], [1.0, 0.0, 0.0, 0.1]], &[0]).unwrap();
    scene.commit().unwrap();

    let hit = scene.intersect(Vec3::new(0.25, 0.0, 5.0), Vec3::NEG_Z, 0.0, f32::INFINITY).expect("a hit");
    assert_eq!(hit.geometry, id);
    assert_eq!(hit.primitive, 0);
    assert!((hit.t - 4.9).abs() < 1e-4, "t = {}", hit.t);
    assert!((hit.u - 0.625).abs() < 1e-3, "u = {}", hit.u);

    // A ray passing beside the tube misses.
    assert!(scene.intersect(Vec3::new(0.0, 0.2, 5.0), Vec3::NEG_Z, 0.0, f32::INFINITY).is_none());
}

/// A ray leaving a tube from inside does not meet it (its far side is not reported: a hair BSDF
/// accounts for the walk through the fibre), for closest-hit and occlusion queries alike; from
/// outside the same tube still blocks.
#[test]
fn rays_from_inside_a_curve_pass_out_of_it() {
    let device = Device::new().unwrap();
    let mut scene = Scene::new(&device).unwrap();
    scene.add_round_linear_curves(&[[-1.0, 0.0, 0.0, 0.1], [1.0, 0.0, 0.0, 0.1]], &[0]).unwrap();
    scene.commit().unwrap();
    for direction in [Vec3::Z, Vec3::NEG_Y, Vec3::new(0.3, 0.5, -0.8).normalize()] {
        let inside = Vec3::new(0.2, 0.0, 0.0);
        assert!(scene.intersect(inside, direction, 0.0, f32::INFINITY).is_none(), "{direction}");
        assert!(!scene.occluded(inside, direction, 0.0, f32::INFINITY), "{direction}");
        let outside = inside - direction * 1.0;
        let hit = scene.intersect(outside, direction, 0.0, f32::INFINITY).expect("the tube from outside");
        assert!((hit.t - (1.0 - 0.1 / 1.0)).abs() < 0.05, "t = {}", hit.t);
        assert!(scene.occluded(outside, direction, 0.0, f32::INFINITY));
    }
}
