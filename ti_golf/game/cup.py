"""When a ball drops into the cup: a closed-form capture rule applied to a simulated path.

The height field has no hole in it (a 108 mm cup is far smaller than its cells), so a stroke is
simulated as if the green were whole and the cup is judged from the ball's path afterwards:

* **Rolling over the cup.** While the ball's centre is over the cup (horizontally within the cup
  radius R_c) the green no longer holds it up, and it falls freely: by g·t²/2 after a time t. Once
  it has dropped by its own radius r, its centre is below the rim, and the far wall of the cup
  stops it rather than lifting it out: it is holed. So a ball that stays over the cup, down on the
  green, for at least the drop time

      t_drop = √(2r/g)                                  (0.066 s for a golf ball)

  drops in. Rolling straight across at speed v, offset b from the cup's centre, it is over the cup
  for 2·√(R_c² − b²)/v, which gives the capture speed

      v_c(b) = 2·√(R_c² − b²)·√(g/(2r))                 (1.64 m/s through the centre)

  the classic figure for a regulation cup (R_c = 54 mm, r = 21.3 mm). The simulated roll over the
  cup is that of a whole green, which slows a ball by about μ_roll·g·t_drop (0.02 m/s): negligible.
* **Coming down into it.** A ball in the air whose bottom comes down to the green while its centre
  is over the cup has dropped into it (rebounds off the rim or the flagstick are not modelled).

A sample is *down on the green* when the ball's gap to the surface is below a tenth of its radius.
Between samples the path is taken to be straight (the samples are a few milliseconds apart: a putt
moves about a centimetre), and the time over the cup is found exactly for that straight path.
"""

from __future__ import annotations

import math

import numpy as np

LOW_GAP = 0.1
"""A ball whose gap to the surface is below this share of its radius is down on the green."""


def drop_time(radius: float, g: float) -> float:
    """t_drop = √(2r/g) [s]: how long a ball of ``radius`` r [m] falls to drop by r under gravity g [m/s²]."""
    return math.sqrt(2.0 * radius / g)


def capture_speed(cup_radius: float, radius: float, g: float, offset: float = 0.0) -> float:
    """v_c = 2·√(R_c² − b²)·√(g/(2r)) [m/s]: the fastest a ball rolling straight across the cup,
    ``offset`` b [m] from its centre, drops in (0 for b ≥ R_c)."""
    chord = 2.0 * math.sqrt(max(cup_radius * cup_radius - offset * offset, 0.0))
    return chord / drop_time(radius, g)


def inside_fractions(xz: np.ndarray, centre: np.ndarray, cup_radius: float) -> tuple[np.ndarray, np.ndarray]:
    """For the straight segments between consecutive points ``xz`` (S, 2) [m], the part s ∈ [s0, s1]
    of each (s from 0 at its start to 1 at its end) that lies within ``cup_radius`` of ``centre``
    (2,): arrays (S − 1,) each, with s0 = s1 where a segment misses the cup. Solves
    |a + s·d|² = R_c² for a = start − centre and d = end − start."""
    a = xz[:-1] - centre
    d = xz[1:] - xz[:-1]
    A = np.einsum("ij,ij->i", d, d)
    B = 2.0 * np.einsum("ij,ij->i", a, d)
    C = np.einsum("ij,ij->i", a, a) - cup_radius * cup_radius
    s0, s1 = np.zeros(len(a)), np.zeros(len(a))
    still = A == 0.0  # a ball that did not move: inside all along or not at all
    s1[still & (C < 0.0)] = 1.0
    disc = B * B - 4.0 * A * C
    cut = ~still & (disc > 0.0)
    root = np.sqrt(np.where(cut, disc, 0.0))
    two_A = np.where(cut, 2.0 * A, 1.0)
    s0[cut] = np.clip((-B[cut] - root[cut]) / two_A[cut], 0.0, 1.0)
    s1[cut] = np.clip((-B[cut] + root[cut]) / two_A[cut], 0.0, 1.0)
    s1 = np.maximum(s1, s0)
    return s0, s1


def holed_at(
    t: np.ndarray,
    x: np.ndarray,
    gap: np.ndarray,
    centre: tuple[float, float],
    cup_radius: float,
    radius: float,
    g: float,
) -> float | None:
    """The time [s] at which a ball that followed the sampled path drops into the cup, or ``None``.

    Args:
        t: sample times (S,) [s], increasing.
        x: ball centres (S, 3) [m] (x, y, z with y up).
        gap: the ball's gap to the surface under it at each sample (S,) [m].
        centre: the cup's centre [x, z] [m].
        cup_radius: the cup's radius R_c [m].
        radius: the ball's radius r [m].
        g: the magnitude of gravity [m/s²].
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return None
    xz = np.asarray(x, dtype=float)[:, [0, 2]]
    c = np.asarray(centre, dtype=float)
    low = np.asarray(gap, dtype=float) < LOW_GAP * radius
    s0, s1 = inside_fractions(xz, c, cup_radius)
    dt = np.diff(t)
    t_drop = drop_time(radius, g)
    run_start, run_end = None, -1.0  # the current stretch over the cup, down on the green
    for k in range(len(dt)):
        over = s1[k] > s0[k]
        if over and not low[k] and low[k + 1]:
            # came down: where along the segment the gap fell below the mark (linear in between)
            g0, g1 = gap[k] - LOW_GAP * radius, gap[k + 1] - LOW_GAP * radius
            s = g0 / (g0 - g1)
            if s0[k] <= s <= s1[k]:
                return float(t[k] + s * dt[k])
        if not (over and low[k] and low[k + 1]):
            run_start = None
            continue
        enter, leave = t[k] + s0[k] * dt[k], t[k] + s1[k] * dt[k]
        if run_start is None or enter > run_end:  # (a new stretch unless it goes on from the last segment)
            run_start = enter
        run_end = leave
        if run_end - run_start >= t_drop:
            return float(run_start + t_drop)
    if run_start is not None and run_end >= t[-1]:  # the ball ended the stroke over the cup
        return float(max(t[-1], run_start + t_drop))
    return None
