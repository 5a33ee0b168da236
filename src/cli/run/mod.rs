//! `adam run`, `adam demo` and `adam soak`: the gait walked by the real-time runtime on the
//! simulated robot (with faults, under an operator) or on the robot over CAN.

mod report;

use crate::cli::paths::{timestamped_log_path, writable};
use crate::cli::shipped;
use anyhow::{bail, Context, Result};
use report::{LogCounts, RobotRunReport};
use std::path::PathBuf;

/// Arguments of `adam run`.
#[derive(clap::Args)]
pub(crate) struct RunArgs {
    /// Where to walk.
    #[arg(long, value_enum)]
    backend: Backend,
    /// Gait file (JSON); default: the co-designed ADAM's.
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: PathBuf,
    /// Runtime config (TOML).
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    config: PathBuf,
    /// Run time, e.g. `30s`, `1500ms` or `30` (seconds); more than 0, at most 24 h.
    #[arg(long, default_value = "30s", value_parser = parse_duration_s)]
    duration: f64,
    /// Treadmill belt speed, m/s (e.g. `0.25`), or a profile of `time:speed` pairs (s, m/s;
    /// e.g. `0:0.20,20:0.30,40:0.25`: from each time the belt ramps to the speed at
    /// --belt-acceleration; without a pair at 0 it starts at rest); every speed inside the
    /// config's `[treadmill] belt_speed_range_mps` (sim; default: the gait's speed).
    #[arg(long, allow_negative_numbers = true)]
    belt: Option<String>,
    /// The belt's ramp acceleration, m/s² (sim; default 0.5).
    #[arg(long)]
    belt_acceleration: Option<f64>,
    /// A push on the torso, `time:force:duration` (s, N with + forward, s), e.g.
    /// `10.5:-20:0.2`; `time:force:duration:phase` lands it at that phase (0–1) of the first
    /// step after the time. Repeatable (sim).
    #[arg(long, allow_negative_numbers = true)]
    push: Vec<String>,
    /// How the simulated run starts: `walk` (in the gait's post-impact state) or `stand`
    /// (standing; Start at 0 s ramps to Stand in 2 s; script a `walk`) (sim; default walk).
    #[arg(long, value_enum)]
    start: Option<Start>,
    /// Operator commands scripted in time, `time:command` pairs (s; start, walk, stop, damp,
    /// reset, estop), e.g. `3:stop,10:walk` (sim).
    #[arg(long)]
    script: Option<String>,
    /// MCAP log file (sim; default: no log); an existing file needs --force.
    #[arg(long)]
    log: Option<PathBuf>,
    /// Write the --log over an existing file.
    #[arg(long)]
    force: bool,
    /// Seed of the simulated IMU and encoder noise (sim; default 1).
    #[arg(long)]
    seed: Option<u64>,
    /// Pace the simulated run by the wall clock at the loop rate and report the loop's
    /// wake-up jitter (sim; default: as fast as the CPU allows). A wall-clock run listens
    /// for operator commands over iceoryx2 (`adam op`).
    #[arg(long)]
    real_time: bool,
    /// Read operator commands from the keyboard, one per line (s start, w walk, p stop,
    /// d damp, r reset, e e-stop); with --real-time.
    #[arg(long, requires = "real_time")]
    keyboard: bool,
    /// CAN interfaces, one per bus of the config (can; default can0,can1,…).
    #[arg(long, value_delimiter = ',')]
    can_interfaces: Option<Vec<String>>,
    /// The torso IMU, `<driver>:<serial port>`: `vn100:/dev/ttyUSB0` (a VectorNav VN-100,
    /// mounted as the config's `[imu]` says) (can).
    #[arg(long)]
    imu: Option<String>,
    /// The motors' CAN-over-UDP address (udp): `HOST:PORT` (bus k at PORT + k) or one address
    /// per bus, comma separated; e.g. `adam emulate motors --listen 127.0.0.1:PORT`'s.
    #[arg(long, value_delimiter = ',')]
    motors: Option<Vec<std::net::SocketAddr>>,
    /// This end's UDP address for bus 0, bus k at its port + k (udp; default: ports the OS
    /// picks); a cannelloni gateway sends to a fixed port (its `-r`).
    #[arg(long)]
    bind: Option<std::net::SocketAddr>,
    /// Inject faults (sim): a profile name (none, loss-0.1, loss-1, loss-10, corrupt-1,
    /// delay-1, soak, rough) or a TOML file; seeded by --seed.
    #[arg(long)]
    faults: Option<String>,
    /// Run the whole loop but send every motor zero torque, logging what the controller would
    /// have sent (sim: the robot hung on the boom, after the pre-flight; Start at 0 s, then
    /// --script).
    #[arg(long)]
    dry_run: bool,
    /// The simulated motors' true zero offsets (joint angle at motor zero, rad, leg order), as
    /// for `adam calibrate` (sim; default 0).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    sim_offsets: Option<Vec<f64>>,
    /// A simulated motor mounted the other way round, by joint; repeatable (sim).
    #[arg(long)]
    sim_flip: Vec<String>,
    /// The live view (sim: paces the run by the wall clock, as --real-time; can).
    #[command(flatten)]
    live: crate::cli::live::LiveFlags,
}

/// Arguments of `adam soak`.
#[derive(clap::Args)]
pub(crate) struct SoakArgs {
    /// Simulated minutes to walk (fractions allowed; more than 0, at most 24 h).
    #[arg(long, value_parser = parse_minutes)]
    minutes: f64,
    /// Fault profile: none, loss-0.1, loss-1, loss-10, corrupt-1, delay-1, soak, rough,
    /// or a TOML file.
    #[arg(long, default_value = "soak")]
    faults: String,
    /// Seed of the faults and the sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Keep each episode's MCAP log in this folder (default: a temporary log, removed).
    #[arg(long)]
    log_dir: Option<PathBuf>,
    /// Gait file (JSON); default: the co-designed ADAM's.
    #[arg(long, default_value = runtime::DEFAULT_GAIT)]
    gait: PathBuf,
    /// Runtime config (TOML).
    #[arg(long, default_value = shipped::RUNTIME_CONFIG)]
    config: PathBuf,
}

/// Arguments of `adam demo`.
#[derive(clap::Args)]
pub(crate) struct DemoArgs {
    /// Treadmill belt speed, m/s, inside the config's `[treadmill] belt_speed_range_mps`
    /// (default: the gait's speed).
    #[arg(long, allow_negative_numbers = true)]
    belt_speed: Option<f64>,
    /// The live view: the demo then walks in real time (30 s of wall clock).
    #[command(flatten)]
    live: crate::cli::live::LiveFlags,
}

/// How a simulated run starts.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Start {
    /// Walking, in the gait's planned post-impact state.
    Walk,
    /// Standing in the gait's first pose.
    Stand,
}

/// The longest run or soak accepted, s (a day).
const MAX_DURATION_S: f64 = 86_400.0;

/// Backend of `adam run`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Backend {
    /// The simulated ADAM on a treadmill behind the simulated A1 firmware and CAN codec.
    Sim,
    /// The robot over SocketCAN.
    Can,
    /// The motors over CAN-over-UDP links (cannelloni's format): `adam emulate motors` in
    /// another process, or cannelloni gateways. Without --real-time the loop runs as fast as the
    /// link answers, in lockstep with the emulator.
    Udp,
}

/// Parses `30s`, `1500ms` or `30` into seconds, more than 0 and at most a day.
pub(crate) fn parse_duration_s(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (number, scale) = if let Some(ms) = t.strip_suffix("ms") {
        (ms, 1e-3)
    } else if let Some(s) = t.strip_suffix('s') {
        (s, 1.0)
    } else {
        (t, 1.0)
    };
    let v: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a duration (expected e.g. 30s, 1500ms)"))?;
    let seconds = v * scale;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("'{text}': the duration must be positive"));
    }
    if seconds > MAX_DURATION_S {
        return Err(format!(
            "'{text}': the duration must be at most 24 h ({MAX_DURATION_S} s)"
        ));
    }
    Ok(seconds)
}

/// Parses `--minutes`: more than 0, at most a day.
fn parse_minutes(text: &str) -> Result<f64, String> {
    let minutes: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number of minutes"))?;
    if !(minutes.is_finite() && minutes > 0.0 && minutes * 60.0 <= MAX_DURATION_S) {
        return Err(format!(
            "'{text}': the minutes must be more than 0 and at most 1440 (24 h)"
        ));
    }
    Ok(minutes)
}

/// The flags of `adam run` given that `backend` does not use, as they are written.
fn unused_flags(backend: Backend, args: &RunArgs) -> Vec<&'static str> {
    let given = |flag: &'static str, set: bool| set.then_some(flag);
    match backend {
        Backend::Sim => [
            given("--can-interfaces", args.can_interfaces.is_some()),
            given("--imu", args.imu.is_some()),
            given("--motors", args.motors.is_some()),
            given("--bind", args.bind.is_some()),
        ]
        .into_iter()
        .flatten()
        .collect(),
        Backend::Udp => [
            given("--belt", args.belt.is_some()),
            given("--belt-acceleration", args.belt_acceleration.is_some()),
            given("--push", !args.push.is_empty()),
            given("--seed", args.seed.is_some()),
            given("--keyboard", args.keyboard),
            given("--can-interfaces", args.can_interfaces.is_some()),
            given("--faults", args.faults.is_some()),
            given("--imu", args.imu.is_some()),
            given("--sim-offsets", args.sim_offsets.is_some()),
            given("--sim-flip", !args.sim_flip.is_empty()),
            given("--live", args.live.live.is_some()),
        ]
        .into_iter()
        .flatten()
        .collect(),
        Backend::Can => [
            given("--belt", args.belt.is_some()),
            given("--belt-acceleration", args.belt_acceleration.is_some()),
            given("--push", !args.push.is_empty()),
            given("--start", args.start.is_some()),
            given("--script", args.script.is_some()),
            given("--seed", args.seed.is_some()),
            given("--real-time", args.real_time),
            given("--keyboard", args.keyboard),
            given("--faults", args.faults.is_some()),
            given("--motors", args.motors.is_some()),
            given("--sim-offsets", args.sim_offsets.is_some()),
            given("--sim-flip", !args.sim_flip.is_empty()),
            given("--bind", args.bind.is_some()),
        ]
        .into_iter()
        .flatten()
        .collect(),
    }
}

/// Checks every speed a simulated run asks of the treadmill: the gait's walking speed (the
/// belt's default), `--belt` and each belt step of the fault profile.
fn check_belt_speeds(
    setup: &runtime::Setup,
    gait: &std::path::Path,
    belt: Option<&Belt>,
    faults: Option<(&str, &runtime::sim::faults::FaultProfile)>,
) -> Result<()> {
    use runtime::sim::faults::Fault;
    let treadmill = &setup.config.treadmill;
    // The gait's speed is the belt's default, and the speed a walk on the lab's treadmill needs.
    treadmill.check_belt_speed(
        &format!(
            "the walking speed of {} (field `speed_mps`)",
            gait.display()
        ),
        setup.gait.speed_mps,
    )?;
    match belt {
        Some(Belt::Constant(v)) => treadmill.check_belt_speed("--belt", *v)?,
        Some(Belt::Profile(p)) => p.check_range(treadmill, "--belt")?,
        None => {}
    }
    if let Some((name, profile)) = faults {
        let events = profile.events.iter().map(|e| e.fault);
        let random = profile
            .random
            .iter()
            .flat_map(|r| r.faults.iter())
            .map(|f| f.fault);
        for fault in events.chain(random) {
            if let Fault::BeltSpeed { speed_mps } = fault {
                treadmill.check_belt_speed(
                    &format!("a belt_speed fault of profile `{name}` (field `speed_mps`)"),
                    speed_mps,
                )?;
            }
        }
    }
    Ok(())
}

/// What `--belt` asks for.
enum Belt {
    /// One speed, m/s.
    Constant(f64),
    /// Speeds in time.
    Profile(runtime::sim::treadmill::BeltProfile),
}

impl Belt {
    /// A number is a constant speed; `time:speed` pairs are a profile.
    fn parse(text: &str) -> Result<Self> {
        if text.contains(':') {
            return Ok(Self::Profile(runtime::sim::treadmill::BeltProfile::parse(
                text, "--belt",
            )?));
        }
        let v: f64 = text.trim().parse().map_err(|_| {
            anyhow::anyhow!(
                "--belt `{text}` is neither a speed in m/s (e.g. 0.25) nor time:speed pairs (e.g. 0:0.20,20:0.30)"
            )
        })?;
        Ok(Self::Constant(v))
    }
}

/// A wall-clock simulated run that takes operator commands over iceoryx2 and, if asked, from
/// the keyboard.
fn sim_walk_operated(
    setup: &runtime::Setup,
    options: &runtime::sim::run::SimWalkOptions,
    keyboard: bool,
) -> Result<()> {
    use runtime::operator::{self, SharedHandle};
    let (handle, receiver) = operator::channel(64);
    let shared = SharedHandle::new(handle);
    let service = operator::operator_service_name(&setup.config.telemetry.service_name);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let forwarder = operator::spawn_iceoryx2_forwarder(&service, shared.clone(), stop.clone())?;
    println!("operator commands: `adam op <command>` (iceoryx2 service {service})");
    if keyboard {
        println!("{}", operator::KEY_HELP);
        // The thread ends with stdin; it is not joined (a blocked read must not hold the exit).
        operator::spawn_keyboard(std::io::BufReader::new(std::io::stdin()), shared);
    }
    let report = runtime::sim::run::walk_with_operator(setup, options, Some(receiver));
    stop.store(true, std::sync::atomic::Ordering::Release);
    let _ = forwarder.join();
    let report = report?;
    println!("{report}");
    if let Some((t, what)) = report.fall {
        bail!("the robot fell ({}) at {t:.3} s", what);
    }
    Ok(())
}

/// Walk in simulation and print the report.
fn sim_walk(setup: &runtime::Setup, options: &runtime::sim::run::SimWalkOptions) -> Result<()> {
    if let Some(dir) = options.log_path.as_ref().and_then(|p| p.parent()) {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
    }
    let report = runtime::sim::run::walk(setup, options)?;
    println!("{report}");
    if let (Some(path), Some(log)) = (&options.log_path, &report.summary.log) {
        let counts = LogCounts {
            records: log.records,
            messages: log.messages,
            dropped: log.dropped,
        };
        println!("log: {} ({counts})", path.display());
    }
    if let Some((t_s, what)) = report.fall {
        bail!("the robot fell ({}) at {t_s:.3} s", what);
    }
    Ok(())
}

/// `adam run --backend sim --dry-run`: the pre-flight, then the loop at zero torque on the
/// simulated robot hung on the boom.
fn sim_dry_run(
    setup: &runtime::Setup,
    duration_s: f64,
    script: &[(f64, runtime::control::OperatorCommand)],
    log: Option<PathBuf>,
) -> Result<()> {
    let dry = runtime::sim::hung::dry_run_sim(setup, duration_s, script, log.clone())?;
    print!("{}", dry.preflight);
    println!("{}", RobotRunReport::of(&dry.summary));
    println!(
        "dry run: every command sent was zero torque; the legs moved {:.2e} rad at most (they \
         hung {} rad off the start pose the controller ramped to)",
        dry.largest_motion_rad,
        runtime::sim::hung::DRY_RUN_START_OFFSET_RAD
    );
    if let (Some(path), Some(stats)) = (&log, &dry.summary.log) {
        let counts = LogCounts {
            records: stats.records,
            messages: stats.messages,
            dropped: stats.dropped,
        };
        println!(
            "log: {} ({counts}): the commands the controller would have sent",
            path.display()
        );
    }
    Ok(())
}

/// `adam demo`: the shipped gait, 30 s on the simulated treadmill, logged under `logs/`.
pub(crate) fn demo(args: &DemoArgs) -> Result<()> {
    let gait = shipped::input(std::path::Path::new(runtime::DEFAULT_GAIT));
    let config = shipped::input(std::path::Path::new(shipped::RUNTIME_CONFIG));
    let setup = runtime::Setup::load(&config, &gait)?;
    check_belt_speeds(&setup, &gait, None, None)?;
    if let Some(v) = args.belt_speed {
        setup.config.treadmill.check_belt_speed("--belt-speed", v)?;
    }
    let g = &setup.gait;
    println!(
        "adam demo: {} (step {:.4} m, {:.4} s, {:.4} m/s) with {}, 30 s on the simulated treadmill (belt {:.3} m/s, 1.6 m long) via SimBus (A1 CAN codec)",
        gait.display(),
        g.step_length_m,
        g.step_duration_s,
        g.speed_mps,
        config.display(),
        args.belt_speed.unwrap_or(g.speed_mps),
    );
    let mut options = runtime::sim::run::SimWalkOptions::new(30.0);
    options.belt_speed_mps = args.belt_speed;
    options.log_path = Some(timestamped_log_path());
    if args.live.live.is_some() {
        // Watched live: in real time, publishing every sample to the viewer.
        options.real_time = true;
        options.publish = true;
        let _viewer = args.live.spawn(&config, &gait, false)?;
        return sim_walk(&setup, &options);
    }
    sim_walk(&setup, &options)
}

/// `adam run`: walks on the chosen backend and prints its report.
pub(crate) fn run(args: RunArgs) -> Result<()> {
    let unused = unused_flags(args.backend, &args);
    if !unused.is_empty() {
        let backend = match args.backend {
            Backend::Sim => "sim",
            Backend::Can => "can",
            Backend::Udp => "udp",
        };
        bail!(
            "{} {} not used by --backend {backend}: remove {}",
            unused.join(", "),
            if unused.len() == 1 { "is" } else { "are" },
            if unused.len() == 1 { "it" } else { "them" },
        );
    }
    let RunArgs {
        backend,
        gait,
        config,
        duration,
        belt,
        belt_acceleration,
        push,
        start,
        script,
        log,
        force,
        seed,
        real_time,
        keyboard,
        can_interfaces,
        imu,
        motors,
        bind,
        faults,
        dry_run,
        sim_offsets,
        sim_flip,
        live,
    } = args;
    let (gait, config) = (shipped::input(&gait), shipped::input(&config));
    let setup = runtime::Setup::load(&config, &gait)?;
    match backend {
        Backend::Sim if dry_run => {
            let ignored: Vec<&str> = [
                ("--belt", belt.is_some()),
                ("--belt-acceleration", belt_acceleration.is_some()),
                ("--push", !push.is_empty()),
                ("--start", start.is_some()),
                ("--seed", seed.is_some()),
                ("--real-time", real_time),
                ("--faults", faults.is_some()),
                ("--sim-offsets", sim_offsets.is_some()),
                ("--sim-flip", !sim_flip.is_empty()),
                ("--live", live.live.is_some()),
            ]
            .iter()
            .filter_map(|(f, set)| set.then_some(*f))
            .collect();
            if !ignored.is_empty() {
                bail!(
                    "{} not used by a --dry-run (the robot hangs on the boom): remove {}",
                    ignored.join(", "),
                    if ignored.len() == 1 { "it" } else { "them" }
                );
            }
            let script = script
                .as_deref()
                .map(|s| runtime::sim::treadmill::parse_script(s, "--script"))
                .transpose()?
                .unwrap_or_default();
            if let Some(path) = &log {
                writable(path, force)?;
            }
            sim_dry_run(&setup, duration, &script, log)
        }
        Backend::Sim => {
            let mut faults = faults
                .as_deref()
                .map(|f| {
                    runtime::sim::faults::FaultProfile::resolve(&shipped::fault_profile(f))
                        .map(|p| (f, p))
                })
                .transpose()?;
            let belt = belt.as_deref().map(Belt::parse).transpose()?;
            check_belt_speeds(
                &setup,
                &gait,
                belt.as_ref(),
                faults.as_ref().map(|(name, p)| (*name, p)),
            )?;
            if let Some(a) = belt_acceleration {
                if !(a.is_finite() && a > 0.0) {
                    bail!("--belt-acceleration {a} m/s²: must be positive and finite");
                }
            }
            let pushes = push
                .iter()
                .map(|p| runtime::sim::treadmill::parse_push(p, "--push"))
                .collect::<runtime::Result<Vec<_>>>()?;
            if !pushes.is_empty() {
                let (_, profile) = faults
                    .get_or_insert_with(|| ("none", runtime::sim::faults::FaultProfile::none()));
                profile.events.extend(pushes);
            }
            let script = script
                .as_deref()
                .map(|s| runtime::sim::treadmill::parse_script(s, "--script"))
                .transpose()?
                .unwrap_or_default();
            if let Some(path) = &log {
                writable(path, force)?;
            }
            let mut options = runtime::sim::run::SimWalkOptions::new(duration);
            match belt {
                Some(Belt::Constant(v)) => options.belt_speed_mps = Some(v),
                Some(Belt::Profile(p)) => options.belt_profile = Some(p),
                None => {}
            }
            if let Some(a) = belt_acceleration {
                options.belt_acceleration_mps2 = a;
            }
            options.start = match start {
                Some(Start::Stand) => runtime::sim::run::SimStart::Stand,
                Some(Start::Walk) | None => runtime::sim::run::SimStart::Walk,
            };
            // From Stand the gains come on at Start: the pre-flight checks the robot first.
            options.preflight = options.start == runtime::sim::run::SimStart::Stand;
            options.encoder_mounts =
                crate::cli::calibrate::sim_mounts(sim_offsets.as_deref(), &sim_flip)?;
            options.script = script;
            options.log_path = log;
            options.seed = seed.unwrap_or(1);
            // The live view watches a run in real time, from the loop's published samples.
            options.real_time = real_time || live.live.is_some();
            options.publish = live.live.is_some();
            options.faults = faults.map(|(_, p)| p);
            let _viewer = live.spawn(&config, &gait, false)?;
            if options.real_time {
                sim_walk_operated(&setup, &options, keyboard)
            } else {
                sim_walk(&setup, &options)
            }
        }
        Backend::Udp => {
            let Some(motors) = motors else {
                bail!("--backend udp needs --motors HOST:PORT (e.g. the address of `adam emulate motors --listen`)");
            };
            if let Some(path) = &log {
                writable(path, force)?;
            }
            let mut options = runtime::udp::UdpRunOptions::new(duration);
            options.start_walking = !matches!(start, Some(Start::Stand));
            options.script = script
                .as_deref()
                .map(|s| runtime::sim::treadmill::parse_script(s, "--script"))
                .transpose()?
                .unwrap_or_default();
            options.real_time = real_time;
            options.bind = bind;
            options.log_path = log.clone();
            let (summary, link) = runtime::udp::walk(&setup, &motors, &options)?;
            println!("{}", RobotRunReport::of(&summary));
            println!(
                "link: {} packets out, {} in; {} IMU samples; dropped: {} from unexpected senders, {} malformed, {} stale; replies not used: {} wrong motor, {} undecodable",
                link.packets_sent, link.packets_received, link.imu_samples, link.foreign_sender,
                link.malformed, link.stale, link.unexpected_replies, link.bad_replies
            );
            if let Some(path) = &log {
                println!("log written: {}", path.display());
            }
            if let Some(trip) = summary.trip {
                bail!("safety trip: {}", trip.name());
            }
            Ok(())
        }
        Backend::Can => {
            let interfaces =
                can_interfaces.unwrap_or_else(|| runtime::robot::default_interfaces(&setup));
            let imu = imu
                .as_deref()
                .map(|text| runtime::robot::ImuSource::parse(text, "--imu"))
                .transpose()?;
            // Everything missing is named here, before the operator channel or a motor moves.
            let log = log.unwrap_or_else(timestamped_log_path);
            writable(&log, force)?;
            let backend = runtime::robot::open(&setup, &interfaces, imu.as_ref())?;
            // The robot run always publishes its samples (`adam op`, the live view).
            let _viewer = live.spawn(&config, &gait, true)?;
            let options = runtime::bringup::RobotRun {
                duration_s: duration,
                dry_run,
                with_held: true,
                log_path: Some(log),
            };
            robot_walk(&setup, backend, &options)
        }
    }
}

/// Walks on the robot under the operator (`adam op`, iceoryx2) and prints the report.
fn robot_walk(
    setup: &runtime::Setup,
    backend: runtime::backend::WithImu<
        drivers::socketcan_bus::SocketCanBus,
        drivers::vn100::port::Vn100,
    >,
    options: &runtime::bringup::RobotRun,
) -> Result<()> {
    use runtime::operator::{self, SharedHandle};
    let (handle, receiver) = operator::channel(64);
    let shared = SharedHandle::new(handle);
    let service = operator::operator_service_name(&setup.config.telemetry.service_name);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let forwarder = operator::spawn_iceoryx2_forwarder(&service, shared, stop.clone())?;
    println!(
        "on the robot: operator commands with `adam op <command>` (iceoryx2 service {service})"
    );
    let result = runtime::robot::walk(setup, backend, options, Some(receiver));
    stop.store(true, std::sync::atomic::Ordering::Release);
    let _ = forwarder.join();
    let (summary, preflight) = result?;
    print!("{preflight}");
    println!("{}", RobotRunReport::of(&summary));
    if let Some(path) = &options.log_path {
        println!("log written: {}", path.display());
    }
    Ok(())
}

/// `adam soak`: walks under random faults, resets after each trip, prints the soak table.
pub(crate) fn soak(args: SoakArgs) -> Result<()> {
    let SoakArgs {
        minutes,
        faults,
        seed,
        log_dir,
        gait,
        config,
    } = args;
    let (config, gait) = (shipped::input(&config), shipped::input(&gait));
    let faults = faults.as_str();
    let profile = runtime::sim::faults::FaultProfile::resolve(&shipped::fault_profile(faults))?;
    let setup = runtime::Setup::load(&config, &gait)?;
    check_belt_speeds(&setup, &gait, None, Some((faults, &profile)))?;
    let options = runtime::sim::run::SoakOptions {
        duration_s: minutes * 60.0,
        profile,
        seed,
        log_dir,
    };
    println!("adam soak: {minutes} min of simulated walking, faults `{faults}`, seed {seed}");
    let wall = std::time::Instant::now();
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let report = runtime::sim::run::soak(&setup, &options, |r| {
        if tty {
            eprint!("\r{:.1} s simulated, {} episodes", r.sim_time_s, r.episodes);
        }
    })?;
    if tty {
        eprintln!();
    }
    print!("{report}");
    println!(
        "wall time                    {:.1} s",
        wall.elapsed().as_secs_f64()
    );
    Ok(())
}
