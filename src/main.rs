//! The `coif` command line: parse, call the library, report. Exit codes: 0 success, 2 bad input
//! or usage, 1 anything else.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use serde_json::json;

use coif::generate::{generate, GenerateParams, Style};
use coif::info::GroomInfo;
use coif::io::{self, ImportOptions, UpAxis};
use coif::{Error, Result};

#[derive(Parser)]
#[command(name = "coif", version, about = "Offline hair-groom styling: perms and wet sets that stay put")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Grow a procedural sample groom on an ellipsoid head.
    Generate(GenerateArgs),
    /// Print strand and vertex counts, bounds, length statistics and attributes of a groom.
    Info {
        file: PathBuf,
        #[command(flatten)]
        import: ImportArgs,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Convert a groom between formats (chosen by extension).
    Convert {
        input: PathBuf,
        output: PathBuf,
        #[command(flatten)]
        import: ImportArgs,
        #[arg(long)]
        json: bool,
    },
    /// Path-trace a preview image of a groom (Embree, Kajiya–Kay hair) to PNG or EXR.
    Render(Box<RenderArgs>),
}

#[derive(Clone, Copy, ValueEnum)]
enum RenderMode {
    /// The path-traced image.
    Beauty,
    /// False colour (blue → red) of the attribute named by --attribute.
    Attribute,
    /// Hair tangents as colour.
    Tangent,
    /// Distance from the camera.
    Depth,
}

#[derive(Clone, Copy, ValueEnum)]
enum SamplerName {
    Sobol,
    Independent,
}

#[derive(Args)]
struct RenderArgs {
    input: PathBuf,
    /// Output image: .png (8-bit sRGB) or .exr (linear float, with --aov channels).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    import: ImportArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 32)]
    spp: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    res: String,
    /// Named viewpoint, framed automatically around the groom (and head).
    #[arg(long, value_enum, default_value_t = coif::render::camera::View::ThreeQuarter)]
    view: coif::render::camera::View,
    /// Explicit camera instead of --view: px,py,pz,tx,ty,tz[,fov] (metres, degrees).
    #[arg(long, allow_hyphen_values = true)]
    camera: Option<String>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = coif::render::camera::DEFAULT_FOV)]
    fov: f32,
    /// Stop after the sample pass during which this many seconds have passed.
    #[arg(long, value_name = "SECONDS")]
    time_budget: Option<f64>,
    /// Worker threads (default: all cores). The image is the same for any count.
    #[arg(long)]
    threads: Option<usize>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[arg(long, value_enum, default_value_t = RenderMode::Beauty)]
    mode: RenderMode,
    /// Attribute to show in false colour (implies --mode attribute), e.g. wetness, bond_hydrogen.
    #[arg(long)]
    attribute: Option<String>,
    /// Value range mapped to blue..red, lo,hi (default: 0,1 for values in [0, 1], else min,max).
    #[arg(long, allow_hyphen_values = true)]
    range: Option<String>,
    /// Hair colour as linear RGB r,g,b in [0, 1] (default: the groom's `color`, else brown).
    #[arg(long)]
    color: Option<String>,
    /// Multiply strand widths (draws hair thicker than it is; 1 = true width).
    #[arg(long, default_value_t = 1.0)]
    width_scale: f32,
    /// Widen strands to at least this many pixels, fading them so average coverage is unchanged.
    #[arg(long, default_value_t = 0.0, value_name = "PIXELS")]
    min_pixel_width: f32,
    /// Show coif's analytic head under the hair.
    #[arg(long, value_enum, default_value_t = coif::render::scene::HeadMode::Auto)]
    head: coif::render::scene::HeadMode,
    /// Leave out the floor.
    #[arg(long)]
    no_floor: bool,
    /// Bounce limit of a path.
    #[arg(long, default_value_t = 8)]
    max_depth: u32,
    /// Exposure, stops.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Direction towards the key light, x,y,z in world space (default: above-left of the camera).
    #[arg(long, allow_hyphen_values = true)]
    light_dir: Option<String>,
    /// Key light irradiance multiplier.
    #[arg(long, default_value_t = 1.0)]
    light_intensity: f32,
    /// Uniform environment radiance instead of the sky (1 = white furnace).
    #[arg(long)]
    environment: Option<f32>,
    #[arg(long, value_enum, default_value_t = SamplerName::Sobol)]
    sampler: SamplerName,
    /// Extra EXR channels: depth, tangent (comma-separated).
    #[arg(long, default_value = "")]
    aov: String,
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct ImportArgs {
    /// Metres per unit of the input file, for formats that do not say (0.01 = centimetres).
    #[arg(long, value_name = "METRES")]
    units: Option<f32>,
    /// Up axis of the input file, for formats that do not say.
    #[arg(long, value_enum)]
    up: Option<UpAxis>,
}

impl ImportArgs {
    fn options(&self) -> ImportOptions {
        ImportOptions { meters_per_unit: self.units, up_axis: self.up }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum StyleName {
    Straight,
    Wavy,
    Curly,
}

#[derive(Args)]
struct GenerateArgs {
    /// Output groom file (.hair).
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, default_value_t = 1000)]
    strands: usize,
    /// Mean strand length, metres.
    #[arg(long, default_value_t = 0.24)]
    length: f32,
    /// Relative spread of strand lengths, in [0, 1).
    #[arg(long, default_value_t = 0.0)]
    length_variation: f32,
    /// Vertices per strand.
    #[arg(long, default_value_t = 16)]
    vertices: usize,
    #[arg(long, value_enum, default_value_t = StyleName::Straight)]
    style: StyleName,
    /// Curl (helix) radius for --style curly, metres.
    #[arg(long, default_value_t = 0.01)]
    curl_radius: f32,
    /// Axial advance per curl turn for --style curly, metres.
    #[arg(long, default_value_t = 0.03)]
    curl_pitch: f32,
    /// Wave amplitude for --style wavy, metres.
    #[arg(long, default_value_t = 0.008)]
    wave_amplitude: f32,
    /// Wavelength for --style wavy, metres.
    #[arg(long, default_value_t = 0.06)]
    wavelength: f32,
    /// Root diameter, metres (strands taper to half at the tip).
    #[arg(long, default_value_t = 80e-6)]
    width: f32,
    /// How fast strands turn downwards, radians per metre.
    #[arg(long, default_value_t = 14.0)]
    droop: f32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("coif: error: {}", error_chain(&error));
            ExitCode::from(error.exit_code() as u8)
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Generate(args) => run_generate(args),
        Command::Info { file, import, json } => {
            let loaded = io::read_groom(&file, &import.options())?;
            let info = GroomInfo::of(&loaded.groom);
            if json {
                print_json(json!({ "path": file, "format": loaded.format, "groom": info }));
            } else {
                print_stdout(&format!("{} ({})\n{info}", file.display(), loaded.format.name()));
            }
            Ok(())
        }
        Command::Convert { input, output, import, json } => {
            let loaded = io::read_groom(&input, &import.options())?;
            write_and_report(&output, &loaded.groom, json)
        }
        Command::Render(args) => run_render(*args),
    }
}

fn run_render(args: RenderArgs) -> Result<()> {
    use coif::render::{self, integrator::Mode, light::Environment, sampler::SamplerKind};
    // Fail on a bad output name before reading or rendering anything.
    render::image::ImageFormat::from_path(&args.output)?;
    let (width, height) = render::parse_resolution(&args.res)?;
    let mode = match (args.mode, &args.attribute) {
        (RenderMode::Beauty | RenderMode::Attribute, Some(name)) => {
            let range = args.range.as_deref().map(render::parse_range).transpose()?;
            Mode::Attribute { name: name.clone(), range }
        }
        (RenderMode::Attribute, None) => {
            return Err(Error::Usage("--mode attribute needs --attribute NAME".into()))
        }
        (RenderMode::Beauty, None) => Mode::Beauty,
        (RenderMode::Tangent, _) => Mode::Tangent,
        (RenderMode::Depth, _) => Mode::Depth,
    };
    let time_budget = match args.time_budget {
        Some(s) if !(s.is_finite() && s > 0.0) => {
            return Err(Error::Usage("--time-budget must be positive seconds".into()))
        }
        s => s.map(std::time::Duration::from_secs_f64),
    };
    let mut settings = render::RenderSettings {
        width,
        height,
        spp: args.spp,
        view: args.view,
        camera: args.camera.as_deref().map(str::parse).transpose()?,
        fov_degrees: args.fov,
        mode,
        max_depth: args.max_depth,
        sampler: match args.sampler {
            SamplerName::Sobol => SamplerKind::Sobol,
            SamplerName::Independent => SamplerKind::Independent,
        },
        seed: args.seed,
        exposure: args.exposure,
        time_budget,
        aovs: render::parse_aovs(&args.aov)?,
        ..Default::default()
    };
    settings.scene.head = args.head;
    settings.scene.floor = !args.no_floor;
    settings.scene.width_scale = args.width_scale;
    settings.scene.min_pixel_width = args.min_pixel_width;
    settings.scene.color = args.color.as_deref().map(|c| render::parse_vec3(c, "--color")).transpose()?;
    settings.key.direction =
        args.light_dir.as_deref().map(|d| render::parse_vec3(d, "--light-dir")).transpose()?;
    settings.key.irradiance *= args.light_intensity;
    if let Some(radiance) = args.environment {
        settings.environment = Environment::Constant(glam::Vec3::splat(radiance));
    }

    let loaded = io::read_groom(&args.input, &args.import.options())?;
    let bar = progress_bar();
    let progress = |done: u64, total: u64| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    };
    let rendered =
        render::with_threads(args.threads, || render::render(&loaded.groom, &settings, &progress))??;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    rendered.image.write(&args.output)?;
    let stats = rendered.stats;
    if args.json {
        print_json(json!({ "output": args.output, "width": width, "height": height, "stats": stats }));
    } else {
        eprintln!(
            "wrote {} ({width}x{height}, {} spp, {:.1} s, {:.2} Mrays/s)",
            args.output.display(),
            stats.spp,
            stats.seconds,
            stats.rays as f64 / stats.seconds.max(1e-9) / 1e6
        );
    }
    Ok(())
}

/// A progress bar on stderr, only when stderr is a terminal (never in logs or pipes).
fn progress_bar() -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(1);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("rendering {bar:40} {percent:>3}% {elapsed}<{eta}")
    {
        bar.set_style(style);
    }
    Some(bar)
}

fn run_generate(args: GenerateArgs) -> Result<()> {
    let style = match args.style {
        StyleName::Straight => Style::Straight,
        StyleName::Wavy => Style::Wavy { amplitude: args.wave_amplitude, wavelength: args.wavelength },
        StyleName::Curly => Style::Curly { radius: args.curl_radius, pitch: args.curl_pitch },
    };
    let params = GenerateParams {
        strands: args.strands,
        length: args.length,
        length_variation: args.length_variation,
        vertices_per_strand: args.vertices,
        style,
        root_width: args.width,
        droop: args.droop,
        seed: args.seed,
        ..Default::default()
    };
    // Fail on an unwritable extension before spending time generating.
    io::Format::from_extension(&args.output)?;
    let groom = generate(&params)?;
    write_and_report(&args.output, &groom, args.json)
}

fn write_and_report(output: &Path, groom: &coif::Groom, json: bool) -> Result<()> {
    let warnings = io::write_groom(output, groom)?;
    for warning in &warnings {
        eprintln!("coif: warning: {warning}");
    }
    let info = GroomInfo::of(groom);
    if json {
        print_json(json!({ "output": output, "groom": info, "warnings": warnings }));
    } else {
        eprintln!("wrote {} ({} strands, {} vertices)", output.display(), info.strands, info.vertices);
    }
    Ok(())
}

fn print_json(value: serde_json::Value) {
    let text = serde_json::to_string_pretty(&value).expect("JSON values always serialise");
    print_stdout(&format!("{text}\n"));
}

/// Prints to stdout; a closed pipe (`coif info x | head`) ends output quietly instead of panicking.
fn print_stdout(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// The error and its causes, one after another, so the user sees the root cause too.
fn error_chain(error: &Error) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !text.contains(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        source = cause.source();
    }
    text
}
