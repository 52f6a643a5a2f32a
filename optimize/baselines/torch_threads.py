"""One PyTorch thread while a torch-based peer runs (Optuna's GPSampler, BoTorch).

torch starts one thread per core; beside other worker processes on a small machine (a 2-core CI, the test suite's
two workers, ``compare`` with workers) the threads fight each other and a run of a few steps takes minutes.  The
previous setting is restored afterwards, so a user's own torch work in the same process is untouched.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["one_torch_thread"]


@contextmanager
def one_torch_thread() -> Iterator[None]:
    """Run the body with ``torch.set_num_threads(1)``, restoring the previous count after."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)
