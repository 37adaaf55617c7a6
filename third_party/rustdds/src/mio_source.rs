// PollEventSource and PollEventSender are an event communication channel that
// carries no data. The receiver is always a mio 1.2 `Source`, and also a mio
// 0.8 `Source` when that optional compatibility feature is enabled.
//
// The internal reactors do not use this channel.

macro_rules! socketpair_bridge {
  ($modname:ident, $mio:ident) => {
    mod $modname {
      use std::{
        io,
        io::{Read, Write},
        sync::{Arc, Mutex},
      };
      #[cfg(not(target_os = "windows"))]
      use std::os::fd::OwnedFd;
      #[cfg(target_os = "windows")]
      use std::{thread::sleep, time::Duration};

      #[allow(unused_imports)]
      use log::{debug, error, info};
      #[cfg(not(target_os = "windows"))]
      use socketpair::{socketpair_stream, SocketpairStream};

      // CompoSuite-ROS patch: the socket pair is made only when the Source is first registered
      // with a poll. Every DataReader has two of these channels and every DataWriter one, and
      // a pair is two file descriptors, so a participant with many endpoints (a process holding
      // 64 environments' nodes: ~25,000 descriptors) ran out of them, although nothing here
      // polls these sources through mio (the async API wakes through Wakers). Until then a send
      // is remembered in `pending` and replayed when the pair is made; no system call is spent.
      struct Pair {
        rec: $mio::net::TcpStream,
        send: $mio::net::TcpStream,
      }

      #[derive(Default)]
      struct Shared {
        pair: Option<Pair>,
        pending: bool,
      }

      pub struct Source {
        shared: Arc<Mutex<Shared>>,
      }

      #[derive(Clone)]
      pub struct Sender {
        shared: Arc<Mutex<Shared>>,
      }

      #[cfg(not(target_os = "windows"))]
      fn set_non_blocking(s: SocketpairStream) -> io::Result<SocketpairStream> {
        let owned_fd = OwnedFd::from(s);
        let std_socket = std::net::TcpStream::from(owned_fd);
        std_socket.set_nonblocking(true)?;
        Ok(SocketpairStream::from(OwnedFd::from(std_socket)))
      }

      #[cfg(not(target_os = "windows"))]
      fn make_pair() -> io::Result<Pair> {
        let (rec_sps, send_sps) = socketpair_stream()?;
        let rec_sps = set_non_blocking(rec_sps)?;
        let send_sps = set_non_blocking(send_sps)?;
        let rec = $mio::net::TcpStream::from_std(std::net::TcpStream::from(OwnedFd::from(rec_sps)));
        let send =
          $mio::net::TcpStream::from_std(std::net::TcpStream::from(OwnedFd::from(send_sps)));
        Ok(Pair { rec, send })
      }

      #[cfg(target_os = "windows")]
      fn make_pair() -> io::Result<Pair> {
        let listener = $mio::net::TcpListener::bind("127.0.0.1:0".parse().unwrap())?;
        let addr = listener.local_addr()?;
        let rec = $mio::net::TcpStream::connect(addr)?;
        let mut accepted = listener.accept();
        while accepted.is_err() {
          sleep(Duration::from_millis(100));
          accepted = listener.accept();
        }
        let (send, _addr_send) = accepted?;
        debug!("IPC socket: {addr:#?} <-> {_addr_send:#?}");
        Ok(Pair { rec, send })
      }

      pub fn make() -> io::Result<(Source, Sender)> {
        let shared = Arc::new(Mutex::new(Shared::default()));
        Ok((
          Source {
            shared: Arc::clone(&shared),
          },
          Sender { shared },
        ))
      }

      fn write_one(pair: &mut Pair) {
        match pair.send.write(&[0xcc]) {
          Ok(_b) => {}
          Err(e) => info!("PollEventSender.send: {e}"),
        }
      }

      impl Sender {
        pub fn send(&self) {
          let mut shared = self.shared.lock().unwrap();
          match shared.pair.as_mut() {
            Some(pair) => write_one(pair),
            None => shared.pending = true,
          }
        }
      }

      impl Source {
        pub fn drain(&self) {
          let mut shared = self.shared.lock().unwrap();
          shared.pending = false;
          let Some(pair) = shared.pair.as_mut() else {
            return;
          };
          let mut buf = Vec::with_capacity(16);
          match pair.rec.read_to_end(&mut buf) {
            Ok(_) => (),
            Err(err) => match err.kind() {
              io::ErrorKind::WouldBlock => {}
              other_kind => info!("PollEventSource.drain(): {other_kind}"),
            },
          }
        }

        // The pair, made now if this is the first registration; a send made before it is
        // replayed so the poll sees it.
        fn with_pair<R>(&self, f: impl FnOnce(&mut Pair) -> io::Result<R>) -> io::Result<R> {
          let mut shared = self.shared.lock().unwrap();
          if shared.pair.is_none() {
            let mut pair = make_pair()?;
            if shared.pending {
              write_one(&mut pair);
            }
            shared.pair = Some(pair);
          }
          f(shared.pair.as_mut().unwrap())
        }
      }

      impl $mio::event::Source for Source {
        fn register(
          &mut self,
          registry: &$mio::Registry,
          token: $mio::Token,
          interests: $mio::Interest,
        ) -> io::Result<()> {
          self.with_pair(|pair| pair.rec.register(registry, token, interests))
        }

        fn reregister(
          &mut self,
          registry: &$mio::Registry,
          token: $mio::Token,
          interests: $mio::Interest,
        ) -> io::Result<()> {
          self.with_pair(|pair| pair.rec.reregister(registry, token, interests))
        }

        fn deregister(&mut self, registry: &$mio::Registry) -> io::Result<()> {
          match self.shared.lock().unwrap().pair.as_mut() {
            Some(pair) => pair.rec.deregister(registry),
            None => Ok(()),
          }
        }
      }
    }
  };
}

#[cfg(feature = "mio_08")]
socketpair_bridge!(bridge_08, mio_08);
socketpair_bridge!(bridge_1, mio1);

pub struct PollEventSource {
  #[cfg(feature = "mio_08")]
  mio08: bridge_08::Source,
  mio1: bridge_1::Source,
}

#[derive(Clone)]
pub struct PollEventSender {
  #[cfg(feature = "mio_08")]
  mio08: bridge_08::Sender,
  mio1: bridge_1::Sender,
}

pub fn make_poll_channel() -> std::io::Result<(PollEventSource, PollEventSender)> {
  #[cfg(feature = "mio_08")]
  let (mio08_source, mio08_sender) = bridge_08::make()?;
  let (mio1_source, mio1_sender) = bridge_1::make()?;
  Ok((
    PollEventSource {
      #[cfg(feature = "mio_08")]
      mio08: mio08_source,
      mio1: mio1_source,
    },
    PollEventSender {
      #[cfg(feature = "mio_08")]
      mio08: mio08_sender,
      mio1: mio1_sender,
    },
  ))
}

impl PollEventSender {
  pub fn send(&self) {
    #[cfg(feature = "mio_08")]
    self.mio08.send();
    self.mio1.send();
  }
}

impl PollEventSource {
  /// Drain sent bytes so the socketpair can trigger again. Call before acting
  /// on the event.
  pub fn drain(&self) {
    #[cfg(feature = "mio_08")]
    self.mio08.drain();
    self.mio1.drain();
  }
}

#[cfg(feature = "mio_08")]
impl mio_08::event::Source for PollEventSource {
  fn register(
    &mut self,
    registry: &mio_08::Registry,
    token: mio_08::Token,
    interests: mio_08::Interest,
  ) -> std::io::Result<()> {
    self.mio08.register(registry, token, interests)
  }

  fn reregister(
    &mut self,
    registry: &mio_08::Registry,
    token: mio_08::Token,
    interests: mio_08::Interest,
  ) -> std::io::Result<()> {
    self.mio08.reregister(registry, token, interests)
  }

  fn deregister(&mut self, registry: &mio_08::Registry) -> std::io::Result<()> {
    self.mio08.deregister(registry)
  }
}

impl mio1::event::Source for PollEventSource {
  fn register(
    &mut self,
    registry: &mio1::Registry,
    token: mio1::Token,
    interests: mio1::Interest,
  ) -> std::io::Result<()> {
    self.mio1.register(registry, token, interests)
  }

  fn reregister(
    &mut self,
    registry: &mio1::Registry,
    token: mio1::Token,
    interests: mio1::Interest,
  ) -> std::io::Result<()> {
    self.mio1.reregister(registry, token, interests)
  }

  fn deregister(&mut self, registry: &mio1::Registry) -> std::io::Result<()> {
    self.mio1.deregister(registry)
  }
}

/// Bounded reader-notification queue with optional mio 0.6 readiness.
#[derive(Clone)]
pub(crate) struct NotificationSender {
  sender: std::sync::mpsc::SyncSender<()>,
  #[cfg(feature = "mio_06")]
  legacy_sender: mio_extras::channel::SyncSender<()>,
}

pub(crate) struct NotificationReceiver {
  receiver: std::sync::mpsc::Receiver<()>,
  #[cfg(feature = "mio_06")]
  legacy_receiver: mio_extras::channel::Receiver<()>,
}

pub(crate) fn notification_channel(capacity: usize) -> (NotificationSender, NotificationReceiver) {
  let (sender, receiver) = std::sync::mpsc::sync_channel(capacity);
  #[cfg(feature = "mio_06")]
  let (legacy_sender, legacy_receiver) = mio_extras::channel::sync_channel(capacity);
  (
    NotificationSender {
      sender,
      #[cfg(feature = "mio_06")]
      legacy_sender,
    },
    NotificationReceiver {
      receiver,
      #[cfg(feature = "mio_06")]
      legacy_receiver,
    },
  )
}

impl NotificationSender {
  pub(crate) fn try_send(&self, value: ()) -> Result<(), std::sync::mpsc::TrySendError<()>> {
    self.sender.try_send(value)?;
    #[cfg(feature = "mio_06")]
    let _ = self.legacy_sender.try_send(());
    Ok(())
  }
}

impl NotificationReceiver {
  pub(crate) fn try_recv(&self) -> Result<(), std::sync::mpsc::TryRecvError> {
    self.receiver.try_recv()
  }
}

#[cfg(feature = "mio_06")]
impl mio_06::Evented for NotificationReceiver {
  fn register(
    &self,
    poll: &mio_06::Poll,
    token: mio_06::Token,
    interest: mio_06::Ready,
    opts: mio_06::PollOpt,
  ) -> std::io::Result<()> {
    self.legacy_receiver.register(poll, token, interest, opts)
  }

  fn reregister(
    &self,
    poll: &mio_06::Poll,
    token: mio_06::Token,
    interest: mio_06::Ready,
    opts: mio_06::PollOpt,
  ) -> std::io::Result<()> {
    self.legacy_receiver.reregister(poll, token, interest, opts)
  }

  fn deregister(&self, poll: &mio_06::Poll) -> std::io::Result<()> {
    self.legacy_receiver.deregister(poll)
  }
}

// CompoSuite-ROS patch tests: the socket pair is made on first registration, and what was sent
// before it is not lost (nor what was drained replayed).
#[cfg(test)]
mod tests {
  use std::time::Duration;

  use mio1::{Events, Interest, Poll, Token};

  use super::make_poll_channel;

  fn readable_after_register(send_before: bool, drain_before: bool) -> bool {
    let (mut source, sender) = make_poll_channel().unwrap();
    if send_before {
      sender.send();
    }
    if drain_before {
      source.drain();
    }
    let mut poll = Poll::new().unwrap();
    poll
      .registry()
      .register(&mut source, Token(7), Interest::READABLE)
      .unwrap();
    let mut events = Events::with_capacity(4);
    poll
      .poll(&mut events, Some(Duration::from_millis(50)))
      .unwrap();
    events
      .iter()
      .any(|e| e.token() == Token(7) && e.is_readable())
  }

  #[test]
  fn a_send_before_the_first_registration_is_seen_by_the_poll() {
    assert!(readable_after_register(true, false));
    assert!(!readable_after_register(false, false));
    assert!(!readable_after_register(true, true));
  }

  #[test]
  fn a_send_after_registration_wakes_the_poll_and_drain_clears_it() {
    let (mut source, sender) = make_poll_channel().unwrap();
    let mut poll = Poll::new().unwrap();
    poll
      .registry()
      .register(&mut source, Token(1), Interest::READABLE)
      .unwrap();
    let mut events = Events::with_capacity(4);
    sender.send();
    poll
      .poll(&mut events, Some(Duration::from_millis(500)))
      .unwrap();
    assert!(events.iter().any(|e| e.token() == Token(1)));
    source.drain();
    poll
      .poll(&mut events, Some(Duration::from_millis(50)))
      .unwrap();
    assert!(events.is_empty());
  }
}
