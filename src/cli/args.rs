//! The command line's grammar: clap derives for every subcommand and flag. The library knows
//! nothing of clap; these types are turned into the library's typed options in `commands`.
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use coif::io::{self, ImportOptions, UpAxis};
use coif::render::{camera::View, scene::HeadMode};

#[derive(Parser)]
#[command(name = "coif", version, about = "Offline hair-groom styling: perms and wet sets that stay put")]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
    /// Refuse jobs whose estimated memory exceeds this (e.g. 8G, 512M; default half the RAM).
    #[arg(long, global = true, value_name = "SIZE")]
    pub(crate) max_memory: Option<String>,
    /// Refuse simulations of more steps than this.
    #[arg(long, global = true, value_name = "STEPS", default_value_t = coif::limits::DEFAULT_MAX_STEPS,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) max_steps: u64,
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
        /// Alembic output for Unreal: centimetres, groom_* attribute names, groom spec version.
        #[arg(long)]
        unreal: bool,
        /// Animated output of these frames of the input's timeline, FIRST:LAST (every whole
        /// frame from FIRST). Default: an animated input's whole frame range; `--frame N` writes
        /// that one frame without time samples.
        #[arg(long, value_name = "FIRST:LAST", conflicts_with = "frame", allow_hyphen_values = true)]
        frame_range: Option<String>,
    },
    /// Simulate a groom (gravity, Cosserat rods, side-chain bonds), optionally settle it, and
    /// write it with its rest shape and bond rates as attributes.
    Simulate(SimulateArgs),
    /// Style a groom with a recipe (perm, water set, blow-dry, bed-head) and settle it into its
    /// new rest shape.
    Style(StyleArgs),
    /// Path-trace a preview image of a groom (Embree, Kajiya–Kay hair) to PNG or EXR.
    Render(Box<RenderArgs>),
    /// Run a job manifest's tasks (grooms × recipes × wedges) locally in parallel, or one task
    /// by index (what a farm array job runs). Complete tasks are skipped, so re-runs resume.
    Batch {
        manifest: PathBuf,
        /// Tasks run at once (each as its own process), at least 1; 0 is refused (as cargo
        /// does), not taken as "all cores".
        #[arg(long, default_value_t = 2)]
        jobs: usize,
        /// Run only this task, in this process.
        #[arg(long)]
        task: Option<usize>,
        #[arg(long)]
        json: bool,
    },
    /// Submit a manifest to a farm scheduler as an array job, or report its progress.
    Farm {
        #[command(subcommand)]
        action: FarmAction,
    },
}

#[derive(Subcommand)]
pub(crate) enum FarmAction {
    /// Write an array job whose task i runs `coif batch MANIFEST --task i`, and submit it.
    Submit {
        manifest: PathBuf,
        #[arg(long, value_enum, default_value_t = Scheduler::Slurm)]
        scheduler: Scheduler,
        #[arg(long)]
        partition: Option<String>,
        /// CPUs per task (and threads coif uses in it).
        #[arg(long, default_value_t = 2)]
        cpus: usize,
        /// Tasks the scheduler may run at once.
        #[arg(long)]
        max_parallel: Option<usize>,
        /// Only write the script (for TDs who submit themselves).
        #[arg(long)]
        dry_run: bool,
        #[arg(long)]
        json: bool,
    },
    /// Which tasks are complete (outputs verified by their sidecars) and which are not.
    Status {
        manifest: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Scheduler {
    Slurm,
}

/// When to show progress on stderr.
#[derive(Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub(crate) enum ProgressArg {
    /// A bar when stderr is a terminal, nothing otherwise (logs, pipes).
    #[default]
    Auto,
    /// Plain lines with the percentage, elapsed time and ETA, one per tenth of the work and at
    /// least every 30 s: for farm and CI logs.
    Log,
    /// Nothing (the same as --quiet).
    Never,
}

impl ProgressArg {
    /// The mode for a run; `--json` and `--quiet` silence the bar, not an explicit `log`.
    pub(crate) fn mode(self, quiet: bool, json: bool) -> coif::progress::ProgressMode {
        use coif::progress::ProgressMode;
        use std::io::IsTerminal;
        match self {
            ProgressArg::Log => ProgressMode::Log,
            ProgressArg::Never => ProgressMode::Off,
            ProgressArg::Auto if quiet || json || !std::io::stderr().is_terminal() => ProgressMode::Off,
            ProgressArg::Auto => ProgressMode::Bar,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum RenderMode {
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
pub(crate) enum LobeArg {
    Chiang,
    KajiyaKay,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum SamplerName {
    Sobol,
    Independent,
}

#[derive(Args)]
pub(crate) struct RenderArgs {
    pub(crate) input: PathBuf,
    /// Output image: .png (8-bit sRGB) or .exr (linear float, with --aov channels).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    #[command(flatten)]
    pub(crate) import: ImportArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 32)]
    pub(crate) spp: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    pub(crate) res: String,
    /// Named viewpoint, framed automatically around the groom (and head).
    #[arg(long, value_enum, default_value_t = ViewArg::ThreeQuarter)]
    pub(crate) view: ViewArg,
    /// Explicit camera instead of --view: px,py,pz,tx,ty,tz[,fov] (metres, degrees).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) camera: Option<String>,
    /// Vertical field of view, degrees.
    #[arg(value_parser = number, long, default_value_t = coif::render::camera::DEFAULT_FOV)]
    pub(crate) fov: f32,
    /// Stop after the sample pass during which this many seconds have passed.
    #[arg(long, value_name = "SECONDS")]
    pub(crate) time_budget: Option<f64>,
    /// Worker threads (default: all cores). The image is the same for any count.
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// No progress bar (--progress never).
    #[arg(long)]
    pub(crate) quiet: bool,
    /// Progress on stderr: auto (a bar on a terminal), log (plain lines with an ETA) or never.
    #[arg(long, value_enum, default_value_t)]
    pub(crate) progress: ProgressArg,
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    #[arg(long, value_enum, default_value_t = RenderMode::Beauty)]
    pub(crate) mode: RenderMode,
    /// Attribute to show in false colour (implies --mode attribute), e.g. wetness, bond_hydrogen.
    #[arg(long)]
    pub(crate) attribute: Option<String>,
    /// Value range mapped to blue..red, lo,hi (default: 0,1 for values in [0, 1], else min,max).
    #[arg(long, allow_hyphen_values = true, requires = "attribute")]
    pub(crate) range: Option<String>,
    /// Hair colour as linear RGB r,g,b in [0, 1] (default: the groom's `color`, else brown).
    #[arg(long)]
    pub(crate) color: Option<String>,
    /// Hair scattering model: kajiya-kay (the preview default) or chiang (physically based:
    /// R, TT, TRT and residual lobes, melanin pigments).
    #[arg(long, value_enum, default_value_t = LobeArg::KajiyaKay)]
    pub(crate) lobe: LobeArg,
    /// Eumelanin concentration, 0 (white) .. 8 (black), 10 at most (chiang lobe; overrides the
    /// groom's colour and `melanin` attribute).
    #[arg(value_parser = number, long)]
    pub(crate) melanin: Option<f32>,
    /// Pheomelanin concentration, 0..10 (red; chiang lobe).
    #[arg(value_parser = number, long)]
    pub(crate) pheomelanin: Option<f32>,
    /// Longitudinal roughness β_m of the chiang lobe, 0.02..1.
    #[arg(value_parser = number, long, default_value_t = 0.3)]
    pub(crate) roughness: f32,
    /// Azimuthal roughness β_n of the chiang lobe, 0.02..1.
    #[arg(value_parser = number, long, default_value_t = 0.3)]
    pub(crate) azimuthal_roughness: f32,
    /// Cuticle scale tilt of the chiang lobe, degrees (-10..10).
    #[arg(value_parser = number, long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub(crate) cuticle_tilt: f32,
    /// Multiply strand widths (draws hair thicker than it is; 1 = true width).
    #[arg(value_parser = number, long, default_value_t = 1.0)]
    pub(crate) width_scale: f32,
    /// Widen strands to at least this many pixels, fading them so average coverage is unchanged.
    #[arg(value_parser = number, long, default_value_t = 0.0, value_name = "PIXELS")]
    pub(crate) min_pixel_width: f32,
    /// Show a head under the hair: the groom's own meshes, else coif's analytic head.
    #[arg(long, value_enum, default_value_t = HeadArg::Auto)]
    pub(crate) head: HeadArg,
    /// Leave out the floor.
    #[arg(long)]
    pub(crate) no_floor: bool,
    /// Floor height (world Y, metres; default: just below the hair and head).
    #[arg(value_parser = number, long, allow_hyphen_values = true, conflicts_with = "no_floor")]
    pub(crate) floor_height: Option<f32>,
    /// Floor edge length, metres (default: a horizon for any view).
    #[arg(value_parser = number, long, conflicts_with = "no_floor")]
    pub(crate) floor_size: Option<f32>,
    /// Floor albedo, linear r,g,b in [0, 1].
    #[arg(long, conflicts_with = "no_floor")]
    pub(crate) floor_albedo: Option<String>,
    /// The shot's camera, lights and floor: a scene file (.toml) or a USD stage (.usda, .usdc)
    /// with a UsdGeom Camera and UsdLux distant, rect and dome lights. Flags given explicitly
    /// override it.
    #[arg(long, value_name = "FILE")]
    pub(crate) scene: Option<PathBuf>,
    /// The camera prim to use when the --scene stage has several, e.g. /shot/cam.
    #[arg(long, value_name = "PRIM")]
    pub(crate) scene_camera: Option<String>,
    /// Bounce limit of a path.
    #[arg(long, default_value_t = 8)]
    pub(crate) max_depth: u32,
    /// Exposure, stops.
    #[arg(value_parser = number, long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(crate) exposure: f32,
    /// Direction towards the key light, x,y,z in world space (default: above-left of the camera).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) light_dir: Option<String>,
    /// Key light irradiance multiplier.
    #[arg(value_parser = number, long, default_value_t = 1.0)]
    pub(crate) light_intensity: f32,
    /// Uniform environment radiance instead of the sky (1 = white furnace).
    #[arg(value_parser = number, long)]
    pub(crate) environment: Option<f32>,
    #[arg(long, value_enum, default_value_t = SamplerName::Sobol)]
    pub(crate) sampler: SamplerName,
    /// Extra EXR channels: depth, tangent (comma-separated).
    #[arg(long, default_value = "")]
    pub(crate) aov: String,
    #[arg(long)]
    pub(crate) json: bool,
}

#[derive(Args)]
pub(crate) struct StyleArgs {
    /// Recipe file (TOML); presets are in grooms/recipes/.
    pub(crate) recipe: PathBuf,
    /// Groom to style.
    #[arg(long)]
    pub(crate) groom: PathBuf,
    /// Styled groom (any format coif writes).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    #[command(flatten)]
    pub(crate) import: ImportArgs,
    /// Print one JSON object (the per-stage report) on stdout.
    #[arg(long)]
    pub(crate) json: bool,
    /// No progress bar (--progress never).
    #[arg(long)]
    pub(crate) quiet: bool,
    /// Progress on stderr: auto (a bar on a terminal), log (plain lines with an ETA) or never.
    #[arg(long, value_enum, default_value_t)]
    pub(crate) progress: ProgressArg,
    /// Also write the whole process as time samples, this many frames per simulated second, 1 to
    /// 10,000 (USD or Alembic output).
    #[arg(value_parser = number, long, value_name = "FPS")]
    pub(crate) frames: Option<f32>,
    /// Style only this curve group (a prim or object path, or its last name); repeatable. The
    /// other groups pass through untouched.
    #[arg(long = "group", value_name = "NAME")]
    pub(crate) groups: Vec<String>,
    /// Simulate this many guides (spread evenly over the scalp) and interpolate the other
    /// strands from them; overrides the recipe's `[guides]`.
    #[arg(long, value_name = "N")]
    pub(crate) guides: Option<usize>,
    /// The groom's scalp or head mesh, a Wavefront OBJ in coif's space (metres, Y up): the
    /// recipe's `shape = "scalp"` obstacles collide with it and its head frame is fitted to it.
    /// Without it, a mesh in the groom file (USD `Mesh`, Alembic `PolyMesh`) under the roots is used.
    #[arg(long, value_name = "OBJ")]
    pub(crate) scalp: Option<PathBuf>,
    /// Output for Unreal, as `convert --unreal` writes it: centimetres, groom_* attribute
    /// names, the groom spec version, the meshes in a sibling file.
    #[arg(long)]
    pub(crate) unreal: bool,
    /// Exit 1 when a settle stage does not reach its tolerance (the output is still written).
    #[arg(long)]
    pub(crate) require_converged: bool,
}

#[derive(Args)]
pub(crate) struct SimulateArgs {
    pub(crate) input: PathBuf,
    pub(crate) output: PathBuf,
    #[command(flatten)]
    pub(crate) import: ImportArgs,
    /// Simulated time, seconds.
    #[arg(value_parser = number, long, default_value_t = 1.0)]
    pub(crate) seconds: f32,
    /// Gravity, m/s² downwards (−Y).
    #[arg(value_parser = number, long, default_value_t = 9.8)]
    pub(crate) gravity: f32,
    /// Solver iterations per step.
    #[arg(long, default_value_t = 5)]
    pub(crate) iterations: u32,
    /// How each iteration solves a strand: `gauss-seidel` sweeps, or `direct` (stretch–shear and
    /// bend–twist together: the static shape does not depend on Δt; one iteration costs ~0.75× a
    /// 5-sweep step and is enough for a falling groom or a bed-head, a perm needs about five).
    #[arg(long, value_enum, default_value_t = coif::sim::StrandSolver::default().into())]
    pub(crate) solver: SolverArg,
    /// Time step, seconds or a fraction.
    #[arg(long, default_value = "1/360", value_parser = time_step)]
    pub(crate) dt: f32,
    /// Velocity damping rate, 1/s.
    #[arg(value_parser = number, long, default_value_t = 2.0)]
    pub(crate) damping: f32,
    /// Bond influences hydrogen,ionic,disulfide,peptide (only ratios matter).
    #[arg(value_parser = number, long, value_delimiter = ',', num_args = 1..=4, default_values_t = coif::sim::BondInfluences::SCENE_3.0)]
    pub(crate) influences: Vec<f32>,
    /// Young's modulus of hair, Pa.
    #[arg(value_parser = number, long, default_value_t = 3.9e9)]
    pub(crate) youngs_modulus: f32,
    /// Solve for static equilibrium after the run (elasticity, gravity, contacts), to
    /// --settle-tolerance or until --settle-seconds of simulated time; the report gives the
    /// residual reached and whether it converged.
    #[arg(long)]
    pub(crate) settle: bool,
    /// Largest accepted net force on a strand (relative to its weight) and net torque over the
    /// groom (relative to gravity's moments), 1e-5 to 0.5. Like the other settle options, it
    /// needs --settle: without it the option would do nothing, unchecked.
    #[arg(value_parser = number, long, default_value_t = coif::sim::settle::DEFAULT_TOLERANCE, requires = "settle")]
    pub(crate) settle_tolerance: f32,
    #[arg(value_parser = number, long, default_value_t = 30.0, requires = "settle")]
    pub(crate) settle_seconds: f32,
    /// Solve for the rest shape that holds the groom's current shape under gravity (for grooms
    /// fresh from a DCC tool), instead of taking the shape, or a styled groom's exported
    /// `rest_darboux`, as the rest shape.
    #[arg(long)]
    pub(crate) sag_free: bool,
    /// Collide with coif's default head (the ellipsoid `coif generate` grows hair on).
    #[arg(long)]
    pub(crate) head: bool,
    /// Strands push each other apart (hair–hair contacts with a recipe's default `[contacts]`),
    /// as a style with `hair_hair = true` simulated them: its strands rest on each other.
    #[arg(long)]
    pub(crate) hair_contacts: bool,
    /// Exit 1 when the settle does not reach its tolerance (the output is still written).
    #[arg(long, requires = "settle")]
    pub(crate) require_converged: bool,
    /// Solver iterations while settling (default: --iterations).
    #[arg(long, requires = "settle")]
    pub(crate) settle_iterations: Option<u32>,
    #[arg(long)]
    pub(crate) json: bool,
}

#[derive(Args)]
pub(crate) struct ImportArgs {
    /// Metres per unit of the input file, for formats that do not say (0.01 = centimetres).
    #[arg(value_parser = number, long, value_name = "METRES")]
    pub(crate) units: Option<f32>,
    /// Up axis of the input file, for formats that do not say.
    #[arg(long, value_enum)]
    pub(crate) up: Option<UpAxisArg>,
    /// Animated input: the frame number to read on the file's own timeline (USD: the time code;
    /// Alembic: time = frame / the file's frame rate). Default: USD's default values (else its
    /// first sample), Alembic's first sample.
    #[arg(long, value_name = "FRAME", allow_negative_numbers = true)]
    pub(crate) frame: Option<f64>,
    /// Animated input: the moment to read, in seconds on the file's own timeline (frame =
    /// seconds × the file's frame rate: USD `timeCodesPerSecond`, else `framesPerSecond`;
    /// Alembic's), the same moment in either format.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, conflicts_with = "frame")]
    pub(crate) time: Option<f64>,
    /// USD input: a variant to select before reading, SET=NAME or /Prim/Path:SET=NAME (repeatable).
    #[arg(long, value_name = "SET=NAME")]
    pub(crate) variant: Vec<String>,
}

impl ImportArgs {
    /// The import options for reading `input` (`--time` becomes that file's frame number).
    pub(crate) fn options(&self, input: &std::path::Path) -> coif::Result<ImportOptions> {
        super::checks::import(self)?;
        let frame = match self.time {
            Some(seconds) => Some(io::timeline::frame_at_time(input, seconds, "--time")?),
            None => self.frame,
        };
        Ok(ImportOptions { meters_per_unit: self.units, up_axis: self.up.map(UpAxis::from), frame })
    }

    /// Whether a moment was picked (`--frame` or `--time`).
    pub(crate) fn picks_a_moment(&self) -> bool {
        self.frame.is_some() || self.time.is_some()
    }

    /// The variants to select (the time comes from [`Self::options`]).
    pub(crate) fn selection(&self) -> io::usda::Selection {
        io::usda::Selection { time: None, variants: self.variant.clone() }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum HairStyle {
    Straight,
    Wavy,
    Curly,
}

#[derive(Args)]
pub(crate) struct GenerateArgs {
    /// Output groom file (.hair).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    #[arg(long, default_value_t = 1000)]
    pub(crate) strands: usize,
    /// Mean strand length, metres.
    #[arg(value_parser = number, long, default_value_t = 0.24)]
    pub(crate) length: f32,
    /// Relative spread of strand lengths, in [0, 1).
    #[arg(value_parser = number, long, default_value_t = 0.0)]
    pub(crate) length_variation: f32,
    /// Vertices per strand.
    #[arg(long, default_value_t = 16)]
    pub(crate) vertices: usize,
    #[arg(long, value_enum, default_value_t = HairStyle::Straight)]
    pub(crate) style: HairStyle,
    /// Curl (helix) radius for --style curly, metres.
    #[arg(value_parser = number, long, default_value_t = 0.01)]
    pub(crate) curl_radius: f32,
    /// Axial advance per curl turn for --style curly, metres.
    #[arg(value_parser = number, long, default_value_t = 0.03)]
    pub(crate) curl_pitch: f32,
    /// Wave amplitude for --style wavy, metres.
    #[arg(value_parser = number, long, default_value_t = 0.008)]
    pub(crate) wave_amplitude: f32,
    /// Wavelength for --style wavy, metres.
    #[arg(value_parser = number, long, default_value_t = 0.06)]
    pub(crate) wavelength: f32,
    /// Root diameter, metres (strands taper to half at the tip).
    #[arg(value_parser = number, long, default_value_t = 80e-6)]
    pub(crate) width: f32,
    /// How fast strands turn downwards, radians per metre.
    #[arg(value_parser = number, long, default_value_t = 14.0)]
    pub(crate) droop: f32,
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    #[arg(long)]
    pub(crate) json: bool,
}

/// `--up`: the file's up axis.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum UpAxisArg {
    Y,
    Z,
}

impl From<UpAxisArg> for UpAxis {
    fn from(arg: UpAxisArg) -> Self {
        match arg {
            UpAxisArg::Y => UpAxis::Y,
            UpAxisArg::Z => UpAxis::Z,
        }
    }
}

/// `--view`: the named viewpoints of auto-framing.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ViewArg {
    /// From the front, slightly above.
    Front,
    /// From the right-hand side.
    Side,
    /// Between front and side, slightly above.
    ThreeQuarter,
    /// From above, the face towards the bottom of the image.
    Top,
    /// From behind: the back of a long groom.
    Back,
}

impl From<ViewArg> for View {
    fn from(arg: ViewArg) -> Self {
        match arg {
            ViewArg::Front => View::Front,
            ViewArg::Side => View::Side,
            ViewArg::ThreeQuarter => View::ThreeQuarter,
            ViewArg::Top => View::Top,
            ViewArg::Back => View::Back,
        }
    }
}

/// `--head`: whether to put a head under the hair: the groom's own meshes, else the analytic
/// head.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum HeadArg {
    /// The meshes the groom's file shows; else the analytic head when the strand roots sit on
    /// coif's default head.
    Auto,
    /// The groom's meshes, hidden ones too; else the analytic head.
    On,
    Off,
}

impl From<HeadArg> for HeadMode {
    fn from(arg: HeadArg) -> Self {
        match arg {
            HeadArg::Auto => HeadMode::Auto,
            HeadArg::On => HeadMode::On,
            HeadArg::Off => HeadMode::Off,
        }
    }
}

/// `--solver`.
#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum SolverArg {
    GaussSeidel,
    Direct,
}

/// The flag's default is the library's ([`coif::sim::StrandSolver`]'s `Default`), not a copy.
impl From<coif::sim::StrandSolver> for SolverArg {
    fn from(solver: coif::sim::StrandSolver) -> Self {
        match solver {
            coif::sim::StrandSolver::GaussSeidel => SolverArg::GaussSeidel,
            coif::sim::StrandSolver::Direct => SolverArg::Direct,
        }
    }
}

impl From<SolverArg> for coif::sim::StrandSolver {
    fn from(arg: SolverArg) -> Self {
        match arg {
            SolverArg::GaussSeidel => coif::sim::StrandSolver::GaussSeidel,
            SolverArg::Direct => coif::sim::StrandSolver::Direct,
        }
    }
}

/// A number flag as `f32` reads it, except that a value beyond `f32`'s range is refused as
/// written rather than read as infinity (`--youngs-modulus 1e40` was refused as "inf").
fn number(text: &str) -> Result<f32, String> {
    let value: f32 = text.trim().parse().map_err(|e| format!("{e}"))?;
    let written_infinite = text.trim().trim_start_matches(['+', '-']).to_ascii_lowercase().starts_with("inf");
    if value.is_infinite() && !written_infinite {
        return Err(format!("{text} is beyond the largest number coif reads ({:e})", f32::MAX));
    }
    Ok(value)
}

/// `--dt`: seconds or a fraction like 1/360.
fn time_step(text: &str) -> Result<f32, String> {
    coif::sim::driver::parse_time_step(text).map_err(|e| e.to_string())
}
