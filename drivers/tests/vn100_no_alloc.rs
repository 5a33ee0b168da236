//! The VN-100 driver's read allocates nothing: over a real pty fed by the emulator (garbage and
//! spoilt frames included), a counting global allocator sees zero allocations on the reading
//! thread over a second of `Imu::read_at` calls that take hundreds of frames.
#![allow(unsafe_code, clippy::unwrap_used)] // the counting allocator must implement GlobalAlloc

use drivers::imu::Imu;
use drivers::vn100::emulator::{serve, Emulator, EmulatorOptions, Pty};
use drivers::vn100::port::Vn100;
use drivers::vn100::Vn100Options;
use std::time::{Duration, Instant};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

#[global_allocator]
static GLOBAL: counting_alloc::Counting = counting_alloc::Counting;

#[test]
fn reading_the_vn100_allocates_nothing() {
    let mut pty = Pty::open().unwrap();
    let path = pty.path().display().to_string();
    let options = EmulatorOptions {
        garbage_probability: 0.05,
        drop_probability: 0.02,
        flip_probability: 0.02,
        ..EmulatorOptions::default()
    };
    let emulator = std::thread::spawn(move || {
        let mut e = Emulator::new(options);
        serve(&mut pty, &mut e, 1.5).map(|c| (c, pty))
    });
    let mut driver = Vn100::open(&path, &Vn100Options::default()).unwrap();
    let start = Instant::now();
    let mut t = 0.0;
    counting_alloc::start();
    while start.elapsed() < Duration::from_secs(1) {
        t += 1e-3;
        let _ = driver.read_at(t);
        std::thread::sleep(Duration::from_micros(500));
    }
    let allocations = counting_alloc::stop();
    let stats = driver.stats();
    // Keep reading until the emulator is done: a full pty would block its writes.
    while !emulator.is_finished() {
        driver.poll();
        std::thread::sleep(Duration::from_millis(1));
    }
    drop(emulator.join().unwrap().unwrap());
    assert!(stats.samples > 500, "{stats:?}");
    assert!(
        stats.parser.crc_failures + stats.parser.bad_headers > 0,
        "{stats:?}"
    );
    assert_eq!(allocations, 0, "{stats:?}");
}
