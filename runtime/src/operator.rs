//! Operator commands into the control thread without ever blocking it.
//!
//! A single-producer single-consumer ring ([`rtrb`], wait-free, allocated once) carries
//! ordinary commands; the emergency stop is a separate latching atomic flag, so it is never
//! lost even when the ring is full, and it is seen first.
//!
//! Two sources feed an [`OperatorHandle`] from their own threads, never from the control
//! thread: the keyboard ([`spawn_keyboard`], one command per line, [`parse_key`]) and iceoryx2
//! ([`spawn_iceoryx2_forwarder`]: [`OperatorMessage`]s on `<telemetry.service_name>/operator`,
//! sent by `adam op <command>` or any other process with [`send_over_iceoryx2`]).

use crate::control::OperatorCommand;
#[cfg(feature = "iceoryx2")]
use iceoryx2::prelude::ZeroCopySend;
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
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("operator queue full, `{}` not sent", command.text())]
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

/// Where operator input threads put commands: an [`OperatorHandle`], or a [`SharedHandle`] when
/// several sources (keyboard and iceoryx2) feed the same loop.
pub trait CommandSink: Send + 'static {
    /// Queue a command (an e-stop latches and is never lost).
    fn send_command(&mut self, command: OperatorCommand) -> Result<(), QueueFull>;
}

impl CommandSink for OperatorHandle {
    fn send_command(&mut self, command: OperatorCommand) -> Result<(), QueueFull> {
        self.send(command)
    }
}

/// An [`OperatorHandle`] shared by several input threads (a mutex on the operator side only;
/// the control thread's end stays wait-free).
#[derive(Clone)]
pub struct SharedHandle(Arc<std::sync::Mutex<OperatorHandle>>);

impl SharedHandle {
    /// Share `handle`.
    pub fn new(handle: OperatorHandle) -> Self {
        Self(Arc::new(std::sync::Mutex::new(handle)))
    }
}

impl CommandSink for SharedHandle {
    fn send_command(&mut self, command: OperatorCommand) -> Result<(), QueueFull> {
        match self.0.lock() {
            Ok(mut h) => h.send(command),
            // A panicked input thread poisoned the lock; the handle itself is still sound.
            Err(poisoned) => poisoned.into_inner().send(command),
        }
    }
}

/// How much the keyboard's `+` and `-` change the speed offset, m/s.
pub const NUDGE_MPS: f64 = 0.025;

/// A keyboard line as a command: `s`/`start`, `w`/`walk`, `p`/`stop`, `d`/`damp`, `r`/`reset`,
/// `e`/`estop`/`x`, `+`/`-` (speed offset ± [`NUDGE_MPS`]), `b 0.25`/`belt 0.25` (belt speed,
/// m/s), `offset 0.05`, `nudge -0.025` (case-insensitive, surrounding blanks ignored); anything
/// else is `None` ([`parse_command`] says why).
pub fn parse_key(line: &str) -> Option<OperatorCommand> {
    parse_command(line).ok()
}

/// [`parse_key`], with an error that says what is wrong (an unknown word, a missing or
/// non-finite speed).
pub fn parse_command(line: &str) -> Result<OperatorCommand, String> {
    let line = line.trim().to_ascii_lowercase();
    let mut words = line.splitn(2, char::is_whitespace);
    let first = words.next().unwrap_or("");
    let rest = words.next().unwrap_or("").trim();
    let unit = |c: OperatorCommand| {
        if rest.is_empty() {
            Ok(c)
        } else {
            Err(format!("`{first}` takes no value (got `{rest}`)"))
        }
    };
    match first {
        "s" => unit(OperatorCommand::Start),
        "w" => unit(OperatorCommand::Walk),
        "p" => unit(OperatorCommand::Stop),
        "d" => unit(OperatorCommand::Damp),
        "r" => unit(OperatorCommand::Reset),
        "e" | "x" | "e-stop" => unit(OperatorCommand::EStop),
        "+" => unit(OperatorCommand::Nudge {
            delta_mps: NUDGE_MPS,
        }),
        "-" => unit(OperatorCommand::Nudge {
            delta_mps: -NUDGE_MPS,
        }),
        "b" => OperatorCommand::parse(&format!("belt {rest}")),
        _ => OperatorCommand::parse(&line),
    }
}

/// The keys [`parse_key`] knows, for a prompt.
pub const KEY_HELP: &str = "keys + Enter: s start, w walk, p stop, d damp, r reset, e e-stop, \
                            b <m/s> belt speed, + / - speed offset ±0.025 m/s";

/// Reads commands from `input` (stdin in the CLI) on a thread of its own until it ends or the
/// ring is gone; unknown lines are reported on stderr. Never touches the control thread.
pub fn spawn_keyboard<R: std::io::BufRead + Send + 'static, H: CommandSink>(
    input: R,
    mut handle: H,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        for line in input.lines() {
            let Ok(line) = line else { break };
            match parse_key(&line) {
                Some(cmd) => {
                    if let Err(e) = handle.send_command(cmd) {
                        eprintln!("operator: {e}");
                    }
                }
                None if line.trim().is_empty() => {}
                None => eprintln!(
                    "operator: `{}`: {} ({KEY_HELP})",
                    line.trim(),
                    parse_command(&line).err().unwrap_or_default()
                ),
            }
        }
    })
}

/// An operator command on the wire: fixed-size, plain old data, for iceoryx2.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "iceoryx2", derive(ZeroCopySend))]
#[repr(C)]
pub struct OperatorMessage {
    /// [`OperatorMessage::code`] of the command.
    pub code: u32,
    /// The value of a valued command (belt speed, offset, nudge), m/s; 0 otherwise.
    pub value_mps: f64,
}

impl OperatorMessage {
    /// The wire code of a command (stable).
    pub fn code(command: OperatorCommand) -> u32 {
        match command {
            OperatorCommand::Start => 1,
            OperatorCommand::Walk => 2,
            OperatorCommand::Stop => 3,
            OperatorCommand::Damp => 4,
            OperatorCommand::Reset => 5,
            OperatorCommand::EStop => 6,
            OperatorCommand::Belt { .. } => 7,
            OperatorCommand::Offset { .. } => 8,
            OperatorCommand::Nudge { .. } => 9,
        }
    }

    /// The message for a command.
    pub fn new(command: OperatorCommand) -> Self {
        Self {
            code: Self::code(command),
            value_mps: command.value_mps().unwrap_or(0.0),
        }
    }

    /// The command, or `None` for an unknown code (a message of another version) or a
    /// non-finite value.
    pub fn command(&self) -> Option<OperatorCommand> {
        if let Some(c) = OperatorCommand::ALL
            .into_iter()
            .find(|&c| Self::code(c) == self.code)
        {
            return Some(c);
        }
        let name = match self.code {
            7 => "belt",
            8 => "offset",
            9 => "nudge",
            _ => return None,
        };
        if !self.value_mps.is_finite() {
            return None;
        }
        OperatorCommand::with_value(name, self.value_mps)
    }
}

/// The iceoryx2 service of operator commands for a runtime publishing on `telemetry_service`.
pub fn operator_service_name(telemetry_service: &str) -> String {
    format!("{telemetry_service}/operator")
}

/// A node and the operator service `name` (opened or created), ports to be made by the caller.
#[cfg(feature = "iceoryx2")]
type OperatorService = (
    iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<
        iceoryx2::prelude::ipc::Service,
        OperatorMessage,
        (),
    >,
);

#[cfg(feature = "iceoryx2")]
fn telemetry_error(service: &str, message: String) -> crate::RuntimeError {
    crate::RuntimeError::Telemetry {
        service: service.to_string(),
        message,
    }
}

#[cfg(feature = "iceoryx2")]
fn open_operator_service(name: &str) -> crate::Result<OperatorService> {
    use iceoryx2::prelude::*;
    let err = |m: String| telemetry_error(name, m);
    let node = crate::telemetry::sample::iceoryx2_node()
        .map_err(|e| err(format!("cannot create a node: {e}")))?;
    let service_name: ServiceName = name
        .try_into()
        .map_err(|e| err(format!("not a valid service name: {e}")))?;
    let service = node
        .service_builder(&service_name)
        .publish_subscribe::<OperatorMessage>()
        .open_or_create()
        .map_err(|e| err(format!("cannot open the service: {e}")))?;
    Ok((node, service))
}

/// Forwards [`OperatorMessage`]s from the iceoryx2 service `service` into `handle`, polling
/// every 5 ms on a thread of its own, until `stop` is set. The service is opened (or created)
/// before this returns, so a message sent after it returns is delivered.
#[cfg(feature = "iceoryx2")]
pub fn spawn_iceoryx2_forwarder<H: CommandSink>(
    service: &str,
    mut handle: H,
    stop: Arc<AtomicBool>,
) -> crate::Result<std::thread::JoinHandle<()>> {
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let name = service.to_string();
    let thread = std::thread::spawn(move || {
        let setup = || -> crate::Result<_> {
            let (node, service) = open_operator_service(&name)?;
            let subscriber = service
                .subscriber_builder()
                .create()
                .map_err(|e| telemetry_error(&name, format!("cannot create a subscriber: {e}")))?;
            Ok((node, service, subscriber))
        };
        let (node, service, subscriber) = match setup() {
            Ok(ports) => {
                let _ = ready_tx.send(Ok(()));
                ports
            }
            Err(e) => {
                let _ = ready_tx.send(Err(e));
                return;
            }
        };
        while !stop.load(Ordering::Acquire) {
            while let Ok(Some(sample)) = subscriber.receive() {
                match sample.payload().command() {
                    Some(cmd) => {
                        if let Err(e) = handle.send_command(cmd) {
                            eprintln!("operator: {e}");
                        }
                    }
                    None => eprintln!(
                        "operator: ignored a message with unknown code {}",
                        sample.payload().code
                    ),
                }
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        drop(subscriber);
        drop(service);
        drop(node);
    });
    match ready_rx.recv() {
        Ok(Ok(())) => Ok(thread),
        Ok(Err(e)) => Err(e),
        Err(_) => Err(crate::RuntimeError::Telemetry {
            service: service.to_string(),
            message: "the forwarder thread ended before opening the service".into(),
        }),
    }
}

/// Sends one command to a runtime's operator service (`adam op`) and returns how many runtimes
/// it reached. The runtime must be running (its forwarder holds a subscriber); a message sent
/// with no subscriber is lost. Takes about 50 ms (the message is held until it is read).
#[cfg(feature = "iceoryx2")]
pub fn send_over_iceoryx2(service: &str, command: OperatorCommand) -> crate::Result<usize> {
    let err = |m: String| telemetry_error(service, m);
    let (node, port) = open_operator_service(service)?;
    let publisher = port
        .publisher_builder()
        .create()
        .map_err(|e| err(format!("cannot create a publisher: {e}")))?;
    let sample = publisher
        .loan_uninit()
        .map_err(|e| err(format!("cannot loan a sample: {e}")))?;
    let sample = sample.write_payload(OperatorMessage::new(command));
    let receivers = sample
        .send()
        .map_err(|e| err(format!("cannot send: {e}")))?;
    // The sample lives in this publisher's shared memory: keep it alive for ten polling periods
    // of the runtime's forwarder (5 ms) so that it is read before this process lets go of it.
    std::thread::sleep(std::time::Duration::from_millis(50));
    drop(publisher);
    drop(port);
    drop(node);
    Ok(receivers)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn keys_parse_to_commands_and_unknown_lines_do_not() {
        assert_eq!(parse_key(" W \n"), Some(OperatorCommand::Walk));
        assert_eq!(parse_key("start"), Some(OperatorCommand::Start));
        assert_eq!(parse_key("e"), Some(OperatorCommand::EStop));
        assert_eq!(parse_key("p"), Some(OperatorCommand::Stop));
        assert_eq!(parse_key("walk please"), None);
        assert_eq!(parse_key(""), None);
        for cmd in OperatorCommand::ALL {
            assert_eq!(OperatorMessage::new(cmd).command(), Some(cmd));
            // Every command's log name is also its keyboard word.
            assert_eq!(parse_key(cmd.name()), Some(cmd));
        }

        assert_eq!(
            OperatorMessage {
                code: 99,
                value_mps: 0.0
            }
            .command(),
            None
        );
        // Speed commands: keys, words, the wire and the log text, and their errors.
        let belt = OperatorCommand::Belt { speed_mps: 0.25 };
        assert_eq!(parse_key("b 0.25"), Some(belt));
        assert_eq!(parse_key(" Belt 0.25 "), Some(belt));
        assert_eq!(
            parse_key("+"),
            Some(OperatorCommand::Nudge {
                delta_mps: NUDGE_MPS
            })
        );
        assert_eq!(
            parse_key("-"),
            Some(OperatorCommand::Nudge {
                delta_mps: -NUDGE_MPS
            })
        );
        for cmd in [
            belt,
            OperatorCommand::Offset { speed_mps: -0.05 },
            OperatorCommand::Nudge {
                delta_mps: 0.1 + 0.2,
            },
        ] {
            assert_eq!(OperatorMessage::new(cmd).command(), Some(cmd));
            assert_eq!(OperatorCommand::parse(&cmd.text()), Ok(cmd));
        }
        let nan = OperatorMessage {
            code: 7,
            value_mps: f64::NAN,
        };
        assert_eq!(nan.command(), None);
        let err = parse_command("belt").unwrap_err();
        assert!(err.contains("needs a speed"), "{err}");
        let err = parse_command("belt fast").unwrap_err();
        assert!(err.contains("`fast` is not a number"), "{err}");
        let err = parse_command("belt inf").unwrap_err();
        assert!(err.contains("not a finite speed"), "{err}");
        let err = parse_command("walk 3").unwrap_err();
        assert!(err.contains("takes no value"), "{err}");
        let err = parse_command("jump").unwrap_err();
        assert!(err.contains("unknown command `jump`"), "{err}");
    }

    #[test]
    fn keyboard_lines_reach_the_control_end_in_order() {
        let (tx, mut rx) = channel(8);
        let input = std::io::Cursor::new("s\nnonsense\n\nw\ne\n");
        spawn_keyboard(input, tx).join().unwrap();
        assert_eq!(rx.poll(), Some(OperatorCommand::EStop));
        assert_eq!(rx.poll(), Some(OperatorCommand::Start));
        assert_eq!(rx.poll(), Some(OperatorCommand::Walk));
        assert_eq!(rx.poll(), None);
    }

    #[cfg(feature = "iceoryx2")]
    #[test]
    fn commands_sent_over_iceoryx2_reach_the_control_end() {
        let name = format!(
            "adam/runtime/test-operator/{}/{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
        );
        let (tx, mut rx) = channel(8);
        let stop = Arc::new(AtomicBool::new(false));
        let forwarder = spawn_iceoryx2_forwarder(&name, tx, stop.clone()).unwrap();
        assert_eq!(
            send_over_iceoryx2(&name, OperatorCommand::Start).unwrap(),
            1
        );
        assert_eq!(send_over_iceoryx2(&name, OperatorCommand::Walk).unwrap(), 1);
        let mut got = Vec::new();
        let t0 = std::time::Instant::now();
        while got.len() < 2 && t0.elapsed() < std::time::Duration::from_secs(5) {
            if let Some(c) = rx.poll() {
                got.push(c);
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        stop.store(true, Ordering::Release);
        forwarder.join().unwrap();
        assert_eq!(got, vec![OperatorCommand::Start, OperatorCommand::Walk]);
    }

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
