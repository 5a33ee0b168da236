//! The live view's input: the control loop's [`StateSample`]s from iceoryx2, in another
//! process. The loop's publisher never waits for this subscriber: when the viewer falls behind
//! by more than [`SUBSCRIBER_BUFFER`] samples, the oldest are overwritten (counted here as gaps
//! in the tick counter).

use crate::telemetry::sample::{
    open_state_service, telemetry_error, StateSample, StateService, SUBSCRIBER_BUFFER,
};
use crate::{Result, RuntimeError};
use iceoryx2::prelude::*;

/// A subscriber of the state service (not `Send`: open it on the thread that reads it).
pub struct SampleSource {
    // Field order = drop order: the port before its service before its node.
    subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, StateSample, ()>,
    _service: StateService,
    _node: iceoryx2::node::Node<ipc::Service>,
    last_tick: Option<u64>,
    missed: u64,
}

impl SampleSource {
    /// Opens (or creates, if the loop has not started yet) the service `name`.
    pub fn open(name: &str) -> Result<Self> {
        let (node, service) = open_state_service(name)?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(SUBSCRIBER_BUFFER)
            .create()
            .map_err(|e| telemetry_error(name, format!("cannot create a subscriber: {e}")))?;
        Ok(Self {
            subscriber,
            _service: service,
            _node: node,
            last_tick: None,
            missed: 0,
        })
    }

    /// Appends every sample waiting to `out`; returns how many.
    pub fn drain(&mut self, out: &mut Vec<StateSample>) -> Result<usize> {
        let mut n = 0;
        loop {
            let received = self
                .subscriber
                .receive()
                .map_err(|e| RuntimeError::Telemetry {
                    service: self.subscriber.id().value().to_string(),
                    message: format!("cannot receive: {e}"),
                })?;
            let Some(sample) = received else {
                return Ok(n);
            };
            let s = *sample.payload();
            if let Some(last) = self.last_tick {
                // A new run restarts the counter: only count forward gaps.
                if s.tick > last + 1 {
                    self.missed += s.tick - last - 1;
                }
            }
            self.last_tick = Some(s.tick);
            out.push(s);
            n += 1;
        }
    }

    /// Samples the loop published that this subscriber never saw (overwritten while it was
    /// behind).
    pub fn missed(&self) -> u64 {
        self.missed
    }
}
