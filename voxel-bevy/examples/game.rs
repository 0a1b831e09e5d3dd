//! World, fly camera (WASD, Space/Shift, arrows turn), a turning glass box, glowing sparks and
//! a Bevy cube; T cycles techniques, N day/night. `cargo run -p voxel-bevy --example game`
use bevy::{camera::Exposure, prelude::*};
use voxel_bevy::voxel_render::Lighting;
use voxel_bevy::*;

fn main() {
    let terrain = voxel_core::TerrainGenerator::new(Default::default());
    let world = VoxelWorld::generated(&terrain, 3).expect("the default terrain");
    App::new()
        .add_plugins((DefaultPlugins, VoxelPlugin::default()))
        .insert_resource(world)
        .add_systems(Startup, setup)
        .add_systems(Update, (fly, keys))
        .run();
}

pub type Keys<'a> = Res<'a, ButtonInput<KeyCode>>;
pub type Assets3d<'a> = (
    ResMut<'a, Assets<Mesh>>,
    ResMut<'a, Assets<StandardMaterial>>,
);

pub fn setup(mut cmd: Commands, (mut mesh, mut mat): Assets3d) {
    let eye = (Transform::from_xyz(0.0, 40.0, 30.0), Exposure::OVERCAST);
    cmd.spawn((Camera3d::default(), VoxelCamera, eye));
    let cube = Mesh3d(mesh.add(Cuboid::from_length(2.0)));
    let red = MeshMaterial3d(mat.add(Color::srgb(0.8, 0.3, 0.2)));
    cmd.spawn((cube, red, Transform::from_xyz(4.0, 34.0, 0.0)));
    let sun = Transform::from_xyz(1.0, 3.0, 2.0).looking_at(Vec3::ZERO, Vec3::Y);
    cmd.spawn((DirectionalLight::default(), sun));
    let glass = VoxelTranslucent::cuboid([2.0; 3], Color::srgb(0.3, 0.8, 0.6), 0.5);
    cmd.spawn((glass, Transform::from_xyz(-4.0, 34.0, 0.0)));
    let spark = VoxelTranslucent::particle(0.1, Color::srgb(1.0, 0.8, 0.3), 0.8);
    let at = |i: u16| Vec3::new((i % 20).into(), (i / 400).into(), (i / 20 % 20).into()) + 28.0;
    let spark = spark.with_emissive(4.0);
    let sparks = (0..800).map(move |i| (spark, Transform::from_translation(at(i))));
    cmd.spawn_batch(sparks);
}

pub fn fly(keys: Keys, time: Res<Time>, mut cam: Single<&mut Transform, With<VoxelCamera>>) {
    let (key, dt) = (|k| f32::from(u8::from(keys.pressed(k))), time.delta_secs());
    cam.rotate_y((key(KeyCode::ArrowLeft) - key(KeyCode::ArrowRight)) * dt);
    cam.rotate_local_x((key(KeyCode::ArrowUp) - key(KeyCode::ArrowDown)) * dt);
    let ahead = cam.forward() * (key(KeyCode::KeyW) - key(KeyCode::KeyS));
    let side = cam.right() * (key(KeyCode::KeyD) - key(KeyCode::KeyA));
    let up = Vec3::Y * (key(KeyCode::Space) - key(KeyCode::ShiftLeft));
    cam.translation += (ahead + side + up) * 12.0 * dt;
}

pub fn keys(keys: Keys, mut t: ResMut<VoxelTechnique>, mut light: ResMut<VoxelLighting>) {
    if keys.just_pressed(KeyCode::KeyT) {
        *t = t.next();
    }
    if keys.just_pressed(KeyCode::KeyN) {
        let night = light.0 == Lighting::daytime(0.0);
        light.0 = Lighting::daytime(if night { 12.0 } else { 0.0 });
    }
}
