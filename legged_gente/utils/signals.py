"""Keep Python's signal handlers in charge after a native library replaced them.

Triton, which torch.compile loads when it first compiles for a GPU, registers LLVM's own SIGINT and SIGTERM
handlers at the C level, over Python's. At the signal they end the process at once, before Python's handler
(training's stop with a save, the viewer's Ctrl-C that finishes a recording) can run. ``signal.signal`` installs
the C-level handler again, so calling it with the handler Python already holds takes the signal back.
"""

from __future__ import annotations

import signal
import threading


def take_back(signums=(signal.SIGINT, signal.SIGTERM)) -> None:
    """Install Python's current handlers for ``signums`` again at the C level. Only the main thread may set
    handlers: elsewhere this does nothing."""
    if threading.current_thread() is not threading.main_thread():
        return
    for signum in signums:
        handler = signal.getsignal(signum)
        if handler is not None:  # None: a handler that Python did not install, which it cannot restore
            signal.signal(signum, handler)
