//! The VN-100 driver over a real pseudo-terminal, the emulated sensor on its master side (in
//! this process; `tests/vn100_tty.rs` runs `adam emulate imu` as another process).

use drivers::imu::Imu;
use drivers::vn100::emulator::{serve, Emulator, EmulatorOptions, Pty};
use drivers::vn100::port::Vn100;
use drivers::vn100::{Vn100Error, Vn100Options};
use std::time::{Duration, Instant};

#[test]
fn a_missing_port_is_named() {
    let err = Vn100::open("/dev/no-such-vn100", &Vn100Options::default())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        err.contains("cannot open the VN-100's serial port `/dev/no-such-vn100`"),
        "{err}"
    );
}

#[test]
fn a_silent_port_names_the_command_it_waited_for() {
    let pty = Pty::open().expect("a pseudo-terminal");
    let options = Vn100Options {
        reply_timeout: Duration::from_millis(100),
        ..Vn100Options::default()
    };
    let path = pty.path().display().to_string();
    match Vn100::open(&path, &options) {
        Err(Vn100Error::NoReply { port, command, .. }) => {
            assert_eq!(port, path);
            // Tried at 921 600 baud, then at the factory rate with the baud command first.
            assert!(command.starts_with("$VNWRG,05,921600"), "{command}");
        }
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("configured without a sensor"),
    }
}

#[test]
fn the_driver_takes_every_intact_frame_and_counts_every_spoilt_one() {
    let mut pty = Pty::open().expect("a pseudo-terminal");
    let path = pty.path().display().to_string();
    let options = EmulatorOptions {
        seed: 7,
        garbage_probability: 0.05,
        drop_probability: 0.02,
        flip_probability: 0.02,
        ..EmulatorOptions::default()
    };
    let emulator = std::thread::spawn(move || {
        let mut e = Emulator::new(options);
        serve(&mut pty, &mut e, 2.0).map(|counts| (counts, pty))
    });
    let mut driver = Vn100::open(&path, &Vn100Options::default()).expect("configured");
    let mut last_new = Instant::now();
    let mut sample = None;
    loop {
        if driver.poll() > 0 {
            last_new = Instant::now();
        }
        if let Some(s) = driver.read_at(0.0) {
            sample = Some(s);
        }
        if emulator.is_finished() && last_new.elapsed() > Duration::from_millis(300) {
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let (sent, _pty) = emulator.join().expect("emulator thread").expect("served");
    let got = driver.stats();
    println!("emulator: {sent}\ndriver: {got:?}");
    assert_eq!(sent.frames_sent, 1600);
    assert!(sent.frames_dropped_byte > 10 && sent.frames_flipped > 10 && sent.garbage_bytes > 500);
    assert_eq!(got.samples, sent.frames_intact);
    assert_eq!(
        got.frames_missed,
        sent.frames_dropped_byte + sent.frames_flipped
    );
    assert_eq!(got.implausible, 0);
    assert_eq!(got.read_errors, 0);
    let s = sample.expect("a sample");
    // At rest leaning 0.05 rad forward, with the default noise (0.05 m/s² per axis).
    assert!((s.accel_z_mps2 - 9.81 * 0.05f64.cos()).abs() < 0.3, "{s:?}");
    assert!((s.accel_x_mps2 + 9.81 * 0.05f64.sin()).abs() < 0.3, "{s:?}");
}
