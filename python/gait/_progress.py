"""Progress of a run: a tqdm bar per pass when tqdm is installed."""


class TqdmProgress:
    """Called with (pass, done, total) as a run goes; one tqdm bar per pass."""

    def __init__(self, tqdm):
        self._tqdm = tqdm
        self._bar = None
        self._pass = None

    def __call__(self, name, done, total):
        if name != self._pass:
            self.close()
            self._bar = self._tqdm(total=total, desc=name, unit="frame")
            self._pass = name
        if total is not None and self._bar.total != total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def close(self):
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def progress_callback(progress):
    """(callback or None, draw gait's own terminal bar) for gait.run's `progress`."""
    if not progress:
        return None, False
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, True
    return TqdmProgress(tqdm), False
