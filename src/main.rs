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
        /// Alembic output for Unreal: centimetres, groom_* attribute names, groom spec version.
        #[arg(long)]
        unreal: bool,
    },
}

#[derive(Args)]
struct ImportArgs {
    /// Metres per unit of the input file, for formats that do not say (0.01 = centimetres).
    #[arg(long, value_name = "METRES")]
    units: Option<f32>,
    /// Up axis of the input file, for formats that do not say.
    #[arg(long, value_enum)]
    up: Option<UpAxis>,
    /// Sample of an animated file to read (0 = first).
    #[arg(long, value_name = "N")]
    frame: Option<u32>,
}

impl ImportArgs {
    fn options(&self) -> ImportOptions {
        ImportOptions { meters_per_unit: self.units, up_axis: self.up, frame: self.frame }
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
        Command::Convert { input, output, import, json, unreal } => {
            let loaded = io::read_groom(&input, &import.options())?;
            write_and_report(&output, &loaded.groom, json, &io::ExportOptions { unreal })
        }
    }
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
    write_and_report(&args.output, &groom, args.json, &io::ExportOptions::default())
}

fn write_and_report(
    output: &Path,
    groom: &coif::Groom,
    json: bool,
    options: &io::ExportOptions,
) -> Result<()> {
    let warnings = io::write_groom_with(output, groom, options)?;
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
