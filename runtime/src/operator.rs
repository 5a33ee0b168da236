//! Operator commands into the control thread without ever blocking it.
//!
//! A single-producer single-consumer ring ([`rtrb`], wait-free, allocated once) carries
//! ordinary commands; the emergency stop is a separate latching atomic flag, so it is never
//! lost even when the ring is full, and it is seen first.

use crate::controller::OperatorCommand;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// The operator's end (any thread; `Send`).
pub struct OperatorHandle {
    ring: rtrb::Producer<OperatorCommand>,
    estop: Arc<AtomicBool>,
}

/// The control thread's end.
pub struct OperatorReceiver {
    ring: rtrb::Consumer<OperatorCommand>,
    estop: Arc<AtomicBool>,
    estop_delivered: bool,
}

/// The ring is full: the control loop is not consuming commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("operator queue full, {command:?} not sent")]
pub struct QueueFull {
    /// The command that was not sent.
    pub command: OperatorCommand,
}

/// A channel for up to `capacity` pending commands.
pub fn channel(capacity: usize) -> (OperatorHandle, OperatorReceiver) {
    let (producer, consumer) = rtrb::RingBuffer::new(capacity.max(1));
    let estop = Arc::new(AtomicBool::new(false));
    (
        OperatorHandle {
            ring: producer,
            estop: estop.clone(),
        },
        OperatorReceiver {
            ring: consumer,
            estop,
            estop_delivered: false,
        },
    )
}

impl OperatorHandle {
    /// Queue a command; [`OperatorCommand::EStop`] goes through the latching flag.
    pub fn send(&mut self, command: OperatorCommand) -> Result<(), QueueFull> {
        if command == OperatorCommand::EStop {
            self.estop();
            return Ok(());
        }
        self.ring.push(command).map_err(|_| QueueFull { command })
    }

    /// Emergency stop: never blocks, never lost.
    pub fn estop(&self) {
        self.estop.store(true, Ordering::Release);
    }
}

impl OperatorReceiver {
    /// The next command, if any: a pending e-stop first (delivered once per raise), then the
    /// ring in order. Wait-free.
    pub fn poll(&mut self) -> Option<OperatorCommand> {
        if self.estop.swap(false, Ordering::AcqRel) {
            self.estop_delivered = true;
            return Some(OperatorCommand::EStop);
        }
        self.ring.pop().ok()
    }

    /// Whether an e-stop was ever delivered.
    pub fn estop_seen(&self) -> bool {
        self.estop_delivered
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn commands_arrive_in_order_and_estop_jumps_the_queue_even_when_full() {
        let (mut tx, mut rx) = channel(2);
        tx.send(OperatorCommand::Start).unwrap();
        tx.send(OperatorCommand::Walk).unwrap();
        assert_eq!(
            tx.send(OperatorCommand::Stop),
            Err(QueueFull {
                command: OperatorCommand::Stop
            })
        );
        tx.send(OperatorCommand::EStop).unwrap();
        assert_eq!(rx.poll(), Some(OperatorCommand::EStop));
        assert_eq!(rx.poll(), Some(OperatorCommand::Start));
        assert_eq!(rx.poll(), Some(OperatorCommand::Walk));
        assert_eq!(rx.poll(), None);
        assert!(rx.estop_seen());
    }

    #[test]
    fn estop_from_another_thread_is_seen() {
        let (tx, mut rx) = channel(4);
        std::thread::spawn(move || tx.estop()).join().unwrap();
        assert_eq!(rx.poll(), Some(OperatorCommand::EStop));
        assert_eq!(rx.poll(), None);
    }
}
