//! The VN-100 driver's read allocates nothing: over a real pty fed by the emulator (garbage and
//! spoilt frames included), a counting global allocator sees zero allocations on the reading
//! thread over a second of `Imu::read_at` calls that take hundreds of frames.
#![allow(unsafe_code, clippy::unwrap_used)] // the counting allocator must implement GlobalAlloc

use drivers::imu::Imu;
use drivers::vn100::emulator::{serve, Emulator, EmulatorOptions, Pty};
use drivers::vn100::port::Vn100;
use drivers::vn100::Vn100Options;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.try_with(Cell::get).unwrap_or(false) {
            let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
    COUNTING.with(|c| c.set(true));
    while start.elapsed() < Duration::from_secs(1) {
        t += 1e-3;
        let _ = driver.read_at(t);
        std::thread::sleep(Duration::from_micros(500));
    }
    COUNTING.with(|c| c.set(false));
    let allocations = ALLOCATIONS.with(Cell::get);
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
