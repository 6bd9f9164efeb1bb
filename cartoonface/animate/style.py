"""Performance styles: how much a face moves around the thesis's announcer statistics.

`STYLES` maps a style name to a `Style`; `PAGE_STYLES` gives each page kind its
default style (the announcer page the restrained one, the audio book the
livelier one). behaviour.schedule, gaze.gaze_actions and idle.sway read
the factors. Every number here is our choice (docs/animation.md, "Styles"):
`announcer` keeps thesis 002's announcer statistics (ch. 4) and adds calm
gaze, rare smiles and a small sway; `storyteller` moves the head about 1.5x as
much and looks away, raises the brows, nods and smiles more often.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Style:
    """Factors and shares of one performance style.

    head: factor on the head angles (tilt, turn, nod depth) and the idle sway.
    sway: peak idle sway in degrees (before `head`), see idle.py.
    brow_rate: factor on the rate of eyebrow raises (their intervals divided by it).
    beat_nods: share of pitch peaks that get a small nod of their own.
    look_away: share of sentences that start with a glance away from the viewer.
    away_hold: (low, high) seconds such a glance lasts, drawn uniformly.
    dart_interval: (low, high) seconds between small eye darts of their own while looking at the viewer.
    head_darts: share of head turns and nods the eyes lead with a dart (gaze.py).
    pause_look: share of long pauses with a look down or aside.
    smile_share: share of sentence ends with a slight smile.
    """

    name: str
    head: float
    sway: float
    brow_rate: float
    beat_nods: float
    look_away: float
    away_hold: tuple[float, float]
    dart_interval: tuple[float, float]
    head_darts: float
    pause_look: float
    smile_share: float

    @property
    def sway_peak(self) -> float:
        """Peak idle sway in degrees with the style's head factor applied (idle.sway's `peak`)."""
        return self.sway * self.head


# A news announcer reads to the camera: Argyle and Cook (1976) find that a speaker
# looks at the listener about 40 % of the time in conversation, but an announcer
# reading from a prompter looks into the lens most of the time, so only a fifth
# of the sentences start with a glance away, and it is short.
ANNOUNCER = Style(name="announcer", head=1.0, sway=0.8, brow_rate=1.0, beat_nods=0.0, look_away=0.2,
                  away_hold=(0.6, 1.5), dart_interval=(5.0, 12.0), head_darts=0.5, pause_look=0.3, smile_share=0.1)
# A storyteller behaves more like a conversational speaker (Kendon 1967: looks
# away at the start of most long utterances and back at their end).
STORYTELLER = Style(name="storyteller", head=1.5, sway=0.8, brow_rate=1.5, beat_nods=0.2, look_away=0.5,
                    away_hold=(0.8, 2.4), dart_interval=(3.0, 8.0), head_darts=0.8, pause_look=0.6, smile_share=0.3)
STYLES = {style.name: style for style in (ANNOUNCER, STORYTELLER)}
PAGE_STYLES = {"announcer": "announcer", "audiobook": "storyteller"}
