use super::config::output_format;
use super::*;
use wgpu::TextureFormat as F;

/// A game moves the renderer to a render thread or keeps it in an ECS resource: it must
/// be `Send` (this fails to compile otherwise).
#[test]
fn renderer_is_send() {
    fn send<T: Send>() {}
    send::<super::Renderer>();
    send::<crate::ChunkStreamer>();
}

#[test]
fn a_view_has_its_texture_format_unless_a_twin_is_declared() {
    assert_eq!(output_format(None, F::Bgra8Unorm), F::Bgra8Unorm);
    assert_eq!(output_format(None, F::Rgba8UnormSrgb), F::Rgba8UnormSrgb);
    let srgb = Some(F::Bgra8UnormSrgb);
    assert_eq!(output_format(srgb, F::Bgra8Unorm), F::Bgra8UnormSrgb);
    assert_eq!(
        output_format(srgb, F::Rgba8Unorm),
        F::Rgba8Unorm,
        "not its twin"
    );
}

#[test]
fn daytime_lighting_is_valid_and_follows_the_sun() {
    let noon = Lighting::daytime(12.0);
    let dusk = Lighting::daytime(Lighting::SUNSET);
    for hour in [f32::NAN, -5.0, 6.0, 9.0, 12.0, 15.0, 18.0, 30.0] {
        Lighting::daytime(hour).validate().unwrap();
    }
    assert!(noon.sun_dir[1] > 0.9 && dusk.sun_dir[1] < 0.2 && dusk.sun_dir[1] > 0.0);
    assert!(
        Lighting::daytime(8.0).sun_dir[0] > 0.0,
        "morning sun in the east"
    );
    assert!(
        Lighting::daytime(16.0).sun_dir[0] < 0.0,
        "afternoon sun in the west"
    );
    assert!(noon.ambient > dusk.ambient);
    assert!(dusk.sky[0] > dusk.sky[2] && noon.sky[2] > noon.sky[0]);
    Lighting::default_day().validate().unwrap();
}

#[test]
fn a_day_has_a_moonlit_night_and_changes_smoothly() {
    let midnight = Lighting::daytime(0.0);
    assert_eq!(midnight.brightness, Lighting::MOONLIGHT);
    assert!(
        midnight.sun_dir[1] > 0.9,
        "the moon stands high at midnight"
    );
    assert!(midnight.sky.iter().all(|&c| c < 0.05), "a dark sky");
    assert_eq!(Lighting::daytime(12.0).brightness, 1.0);
    assert_eq!(
        Lighting::daytime(-12.0),
        Lighting::daytime(12.0),
        "hours modulo 24"
    );
    // Through a whole day minute by minute, the light on no face and the sky
    // jump.
    let face_light = |l: &Lighting| -> Vec<f32> {
        let sun = glam::Vec3::from(l.sun_dir).normalize();
        let normals = [
            glam::Vec3::X,
            glam::Vec3::NEG_X,
            glam::Vec3::Y,
            glam::Vec3::NEG_Y,
        ];
        let lambert = |n: glam::Vec3| l.ambient + (1.0 - l.ambient) * n.dot(sun).max(0.0);
        let more = [glam::Vec3::Z, glam::Vec3::NEG_Z];
        normals
            .iter()
            .chain(&more)
            .map(|&n| l.brightness * lambert(n))
            .collect()
    };
    let mut last = Lighting::daytime(0.0);
    for step in 1..=1440 {
        let hour = step as f32 / 60.0;
        let l = Lighting::daytime(hour);
        l.validate().unwrap();
        assert!((Lighting::MOONLIGHT..=1.0).contains(&l.brightness));
        let (now, before) = (face_light(&l), face_light(&last));
        let light = now
            .iter()
            .zip(&before)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        let sky = (0..3)
            .map(|i| (l.sky[i] - last.sky[i]).abs())
            .fold(0.0, f32::max);
        assert!(light < 0.05 && sky < 0.05, "hour {hour}: {last:?} -> {l:?}");
        last = l;
    }
}
