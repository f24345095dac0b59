//! [`IgLink`]: the IG session shared between the UDP receiver thread (which feeds it each
//! accepted message under a short lock) and the frame loop (which calls
//! [`begin_frame`](IgLink::begin_frame) once at the start of every IG frame and gets the
//! frame's datagrams sent on the receiver's socket).
//!
//! The terrain is asked with the session unlocked (its work is copied out first), so a frame
//! with many requests never holds up the receiver thread — and with it the poses' arrival
//! times.

use std::net::{SocketAddr, UdpSocket};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use crate::codec::cigi::CigiMessage;
use crate::query::{TerrainQueries, TerrainRequest};
use crate::stats::Counters;

use super::entities::EntityTable;
use super::session::{FrameAnswers, IgConfig, IgFrame, IgSession, IgState, Received};
use super::stats::IgStats;

struct Shared {
    session: Mutex<IgSession>,
    /// A clone of the receiver's socket: answers leave from the port the host sends to.
    socket: Option<UdpSocket>,
    /// The input's counters (Start of Frames sent are counted there too).
    counters: Option<Arc<Counters>>,
}

/// A handle on one IG session; clones share it.
#[derive(Clone)]
pub struct IgLink {
    shared: Arc<Shared>,
}

impl std::fmt::Debug for IgLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IgLink")
            .field(
                "socket",
                &self
                    .shared
                    .socket
                    .as_ref()
                    .and_then(|s| s.local_addr().ok()),
            )
            .finish_non_exhaustive()
    }
}

impl IgLink {
    /// A link sending on `socket` (none: [`begin_frame`](Self::begin_frame) only returns the
    /// datagrams), counting Start of Frames in `counters`.
    pub fn new(
        config: IgConfig,
        socket: Option<UdpSocket>,
        counters: Option<Arc<Counters>>,
    ) -> Self {
        Self {
            shared: Arc::new(Shared {
                session: Mutex::new(IgSession::new(config)),
                socket,
                counters,
            }),
        }
    }

    fn session(&self) -> MutexGuard<'_, IgSession> {
        // A panic elsewhere while holding the lock leaves a consistent session (every change
        // is a plain assignment): keep serving it.
        self.shared
            .session
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Takes an accepted CIGI message from `from` (the receiver thread).
    pub fn receive(&self, m: &CigiMessage, from: SocketAddr) -> Received {
        self.session().receive(m, from)
    }

    /// Takes a native terrain query from `from` (the receiver thread).
    pub fn receive_native(&self, id: u32, request: TerrainRequest, from: SocketAddr) {
        self.session().receive_native(id, request, from);
    }

    /// Starts IG frame `f`: answers what is due from `terrain` and sends the frame's
    /// datagrams (Start of Frame first). Call once at the start of every frame.
    pub fn begin_frame(&self, f: &IgFrame, terrain: &dyn TerrainQueries) -> FrameAnswers {
        let t0 = Instant::now();
        let work = self.session().prepare(f);
        let asked = work.ask(terrain);
        let mut answers = self.session().finish(asked);
        answers.cpu_us = t0.elapsed().as_secs_f64() * 1e6;
        let mut errors = 0;
        if let Some(socket) = &self.shared.socket {
            for (i, d) in answers.datagrams.iter().enumerate() {
                match socket.send_to(&d.bytes, d.to) {
                    Ok(_) => {
                        if i == 0 && answers.start_of_frame {
                            if let Some(c) = &self.shared.counters {
                                c.reply();
                            }
                        }
                    }
                    Err(e) => {
                        errors += 1;
                        tracing::debug!("IG answer to {}: {e}", d.to);
                    }
                }
            }
        }
        let mut s = self.session();
        s.record_cpu_us(answers.cpu_us);
        s.record_send_errors(errors);
        answers
    }

    /// The host-visible state (mode, resets, database request, environment, host version).
    pub fn state(&self) -> IgState {
        self.session().state()
    }

    /// Counters.
    pub fn stats(&self) -> IgStats {
        self.session().stats()
    }

    /// A copy of the entity table.
    pub fn entities(&self) -> EntityTable {
        self.session().entities().clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::cigi::{self, decode_ig_message, IgControl};
    use crate::codec::ByteOrder;
    use crate::ig::session::DatabaseStatus;
    use crate::query::NoTerrain;

    #[test]
    fn clones_share_one_session_and_answers_are_sent() {
        let ig = UdpSocket::bind("127.0.0.1:0").unwrap();
        let host = UdpSocket::bind("127.0.0.1:0").unwrap();
        host.set_read_timeout(Some(std::time::Duration::from_secs(5)))
            .unwrap();
        let counters = Arc::new(Counters::default());
        let link = IgLink::new(
            IgConfig::default(),
            Some(ig.try_clone().unwrap()),
            Some(counters.clone()),
        );
        let other = link.clone();
        let m = cigi::decode(
            &IgControl {
                ig_mode: 1,
                host_frame: 41,
                ..IgControl::default()
            }
            .encode(ByteOrder::Big),
        )
        .unwrap();
        other.receive(&m, host.local_addr().unwrap());
        let f = IgFrame {
            ig_frame: 9,
            time_s: 1.0,
            database: DatabaseStatus::Ready(2),
        };
        let a = link.begin_frame(&f, &NoTerrain);
        assert!(a.start_of_frame && a.cpu_us >= 0.0);
        let mut buf = [0u8; 256];
        let (n, from) = host.recv_from(&mut buf).unwrap();
        assert_eq!(from, ig.local_addr().unwrap());
        let msg = decode_ig_message(&buf[..n]).unwrap();
        assert_eq!(
            (
                msg.start_of_frame.ig_frame,
                msg.start_of_frame.last_host_frame
            ),
            (9, 41)
        );
        assert_eq!(msg.byte_order, ByteOrder::Big);
        assert_eq!(counters.snapshot().replies, 1);
        let s = other.stats();
        assert_eq!((s.start_of_frames, s.cpu_frames, s.send_errors), (1, 1, 0));
        assert_eq!(other.state().last_host_frame, Some(41));
    }
}
