"""The text prompt generators write beside a motion file: ``name.txt`` next to ``name.npy``.

MLD and its forks write ``{task}_{len}_batch{b}_{i}.npy`` with the prompt in ``.txt`` beside it;
MotionGPT writes ``{id}_out.npy`` with ``{id}_out.txt``. A file with one line per clip gives each
clip its own prompt; otherwise the whole text is every clip's prompt.
"""

from __future__ import annotations

from pathlib import Path

#: Larger .txt files beside a motion are not prompts (a log, a manifest): ignored.
MAX_PROMPT_BYTES = 16384


def prompts_beside(path: Path, clips: int) -> list[str | None]:
    """One prompt (or None) per clip from ``path.with_suffix('.txt')``, if that file exists."""
    txt = path.with_suffix(".txt")
    try:
        if not txt.is_file() or txt.stat().st_size > MAX_PROMPT_BYTES:
            return [None] * clips
        text = txt.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return [None] * clips
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        return [None] * clips
    if clips > 1 and len(lines) == clips:
        return lines
    return [" ".join(lines)] * clips
