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
