//! Single-key commands for `bag play` when stdin is a terminal: the terminal is switched to
//! non-canonical, no-echo mode (signals stay on, so Ctrl-C still stops playback) and restored
//! when the guard drops. Keys arrive on a channel from a reader thread.

use std::io::Read;
use std::os::fd::AsFd;
use std::sync::mpsc::{channel, Receiver};

use nix::sys::termios::{tcgetattr, tcsetattr, LocalFlags, SetArg, Termios};

pub struct Keyboard {
    saved: Termios,
    pub keys: Receiver<u8>,
}

impl Keyboard {
    /// `None` when stdin is not a terminal (piped input, tests, launch files).
    pub fn open() -> Option<Keyboard> {
        let stdin = std::io::stdin();
        if !nix::unistd::isatty(stdin.as_fd()).unwrap_or(false) {
            return None;
        }
        let saved = tcgetattr(stdin.as_fd()).ok()?;
        let mut raw = saved.clone();
        raw.local_flags
            .remove(LocalFlags::ICANON | LocalFlags::ECHO);
        tcsetattr(stdin.as_fd(), SetArg::TCSANOW, &raw).ok()?;
        let (tx, keys) = channel();
        std::thread::spawn(move || {
            let mut byte = [0u8; 1];
            while std::io::stdin().read_exact(&mut byte).is_ok() {
                if tx.send(byte[0]).is_err() {
                    break;
                }
            }
        });
        Some(Keyboard { saved, keys })
    }
}

impl Drop for Keyboard {
    fn drop(&mut self) {
        let _ = tcsetattr(std::io::stdin().as_fd(), SetArg::TCSANOW, &self.saved);
    }
}
