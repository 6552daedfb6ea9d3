//! `lpc render`: numbered PNG frames with no window and no display. Bevy renders into an
//! `Image` target and a `Screenshot` of that image is read back and written per frame; on a
//! CPU-only machine wgpu runs on Mesa's lavapipe (software Vulkan), on a GPU machine on the GPU.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, PipelineCache, PollType, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::renderer::RenderDevice;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::render::{RenderApp, RenderPlugin};

use super::stage::{pose, spawn_stage, Layout, Playback, BACKGROUND};
use crate::run::Run;
use crate::scene::Scene;

/// What to render.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Directory for `frame_00000.png`, ...
    pub out: PathBuf,
    /// Image size in pixels (width, height).
    pub size: (u32, u32),
    /// Samples of the run between two frames (the run is sampled so that frames fall on samples).
    pub samples_per_frame: usize,
}

/// Rendering failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU adapter (install Mesa's lavapipe: `mesa-vulkan-drivers`, `libvulkan1`).
    #[error("no graphics adapter: install a GPU driver or Mesa's software Vulkan (Debian: mesa-vulkan-drivers libvulkan1)")]
    NoAdapter,
    /// A frame could not be written.
    #[error("writing {path}: {reason}")]
    Write {
        /// The frame's path.
        path: String,
        /// Why.
        reason: String,
    },
}

/// Updates the app and waits until the GPU has finished what it submitted, so that the
/// frame's readback completes in order.
fn update_and_wait(app: &mut App) {
    app.update();
    if let Some(device) = app.world().get_resource::<RenderDevice>() {
        let _ = device.wgpu_device().poll(PollType::Wait { submission_index: None, timeout: None });
    }
}

/// A windowless app that renders `scene` posed by `run` into an image of `size`.
fn app_for(scene: &Scene, run: Run, size: (u32, u32)) -> Result<(App, Handle<Image>), RenderError> {
    // Bevy panics when it finds no adapter; that is a missing driver, reported as an error.
    let quiet = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let started = std::panic::catch_unwind(|| {
        let mut app = App::new();
        app.add_plugins(
            DefaultPlugins
                .set(WindowPlugin { primary_window: None, exit_condition: bevy::window::ExitCondition::DontExit, ..default() })
                .set(RenderPlugin { synchronous_pipeline_compilation: true, ..default() })
                .disable::<bevy::log::LogPlugin>()
                // No event loop: it would need a display.
                .disable::<bevy::winit::WinitPlugin>(),
        );
        // Not `app.run()`: the frames are driven one by one, as the default runner would.
        while app.plugins_state() == bevy::app::PluginsState::Adding {
            bevy::tasks::tick_global_task_pools_on_main_thread();
        }
        app.finish();
        app.cleanup();
        app
    });
    std::panic::set_hook(quiet);
    let mut app = started.map_err(|_| RenderError::NoAdapter)?;
    if app.world().get_resource::<RenderDevice>().is_none() {
        return Err(RenderError::NoAdapter);
    }
    let mut target = Image::new_uninit(
        Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
        TextureDimension::D2,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    target.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC | TextureUsages::TEXTURE_BINDING;
    let target = app.world_mut().resource_mut::<Assets<Image>>().add(target);
    let layout = Layout::of(scene);
    app.insert_resource(layout.clone())
        .insert_resource(Playback::new(run))
        .add_systems(PostUpdate, pose.before(TransformSystems::Propagate));
    let world = app.world_mut();
    world.resource_scope(|world, mut meshes: Mut<Assets<Mesh>>| {
        world.resource_scope(|world, mut materials: Mut<Assets<StandardMaterial>>| {
            let mut commands = world.commands();
            spawn_stage(&mut commands, &mut meshes, &mut materials, scene, &layout);
            commands.spawn((
                Camera3d::default(),
                // An analytic tone mapper: the default one needs lookup-table features.
                Tonemapping::AcesFitted,
                Camera { clear_color: ClearColorConfig::Custom(Color::srgb_u8(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2])), ..default() },
                RenderTarget::Image(target.clone().into()),
                layout.camera(),
            ));
        });
    });
    world.flush();
    Ok((app, target))
}

/// Renders one frame per `options.samples_per_frame` samples of `run` (a run of `scene`) into
/// `options.out`; returns the frames' paths in order.
pub fn render_frames(scene: &Scene, run: &Run, options: &RenderOptions) -> Result<Vec<PathBuf>, RenderError> {
    let write_err = |path: &Path, reason: String| RenderError::Write { path: path.display().to_string(), reason };
    std::fs::create_dir_all(&options.out).map_err(|e| write_err(&options.out, e.to_string()))?;
    let (mut app, target) = app_for(scene, run.clone(), options.size)?;
    // Until every pipeline has compiled, frames come out with meshes missing.
    let mut quiet = 0;
    for _ in 0..300 {
        update_and_wait(&mut app);
        let cache = app.sub_app(RenderApp).world().resource::<PipelineCache>();
        let idle = cache.waiting_pipelines().count() == 0 && cache.pipelines().count() > 0;
        quiet = if idle { quiet + 1 } else { 0 };
        if quiet >= 3 {
            break;
        }
    }
    let samples = run.series.len();
    let frames: Vec<usize> = (0..samples).step_by(options.samples_per_frame.max(1)).collect();
    let errors: Arc<Mutex<Vec<RenderError>>> = Arc::default();
    let done = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let mut paths = vec![];
    for (k, &sample) in frames.iter().enumerate() {
        app.world_mut().resource_mut::<Playback>().sample = sample;
        let path = options.out.join(format!("frame_{k:05}.png"));
        paths.push(path.clone());
        let (errors, done) = (errors.clone(), done.clone());
        app.world_mut().spawn(Screenshot::image(target.clone())).observe(move |shot: On<ScreenshotCaptured>| {
            // Written beside and renamed: a frame on disk is always a whole frame.
            let tmp = path.with_extension("tmp.png");
            let saved = shot
                .image
                .clone()
                .try_into_dynamic()
                .map_err(|e| e.to_string())
                .and_then(|img| img.to_rgb8().save(&tmp).map_err(|e| e.to_string()))
                .and_then(|()| std::fs::rename(&tmp, &path).map_err(|e| e.to_string()));
            if let Err(reason) = saved {
                errors.lock().expect("not poisoned").push(RenderError::Write { path: path.display().to_string(), reason });
            }
            done.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        });
        update_and_wait(&mut app);
    }
    // Readbacks finish a frame or two later.
    for _ in 0..100 {
        if done.load(std::sync::atomic::Ordering::SeqCst) >= frames.len() {
            break;
        }
        update_and_wait(&mut app);
    }
    if let Some(e) = errors.lock().expect("not poisoned").drain(..).next() {
        return Err(e);
    }
    if done.load(std::sync::atomic::Ordering::SeqCst) < frames.len() {
        return Err(write_err(&options.out, "the renderer never delivered every frame".into()));
    }
    Ok(paths)
}
