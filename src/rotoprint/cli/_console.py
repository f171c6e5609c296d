"""The rich consoles of the command (stderr for messages, stdout for results); a module of its
own so that the fast ``rotoprint dlp`` entry imports rich only when it shows something on a
terminal."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.text import Text

from ._base import escape_controls


class _SafeConsole(Console):
    """A Console whose strings have their control characters escaped (see :func:`escape_controls`);
    rich's own styling codes are added after, so colours still work."""

    def render_str(self, text: str, **kwargs: Any) -> Text:
        return super().render_str(escape_controls(text, keep_newlines=True), **kwargs)

    # Where the output is not a terminal (a pipe, a file, a CI log) rich would wrap every
    # line at 80 columns, and a path a user copies from a summary would come with a newline
    # in it: there lines are printed whole (soft wrap), as the error lines always were. On a
    # terminal rich wraps at its width as before (the terminal's own width, not a fixed 80).
    @property
    def soft_wrap(self) -> bool:
        return self._soft_wrap_default or not self.is_terminal

    @soft_wrap.setter
    def soft_wrap(self, value: bool) -> None:
        self._soft_wrap_default = bool(value)


# No markup and no emoji codes: paths and option values are printed as they are (a "[" or
# ":b:" in a file name must not be read as rich markup). Styles go through rich.text.Text.
console = _SafeConsole(stderr=True, highlight=False, markup=False, emoji=False)
out_console = _SafeConsole(highlight=False, markup=False, emoji=False)
