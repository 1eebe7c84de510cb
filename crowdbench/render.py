"""Offscreen rendering of world 0 with Pillow (no display needed) and animated-GIF writing.

Rendering only reads the world's state: it never changes what the simulation does.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw

from crowdbench.io import atomic_path

ROBOT = (230, 160, 20)
HUMAN = (70, 110, 200)
RESPONSIVE = (40, 170, 90)
OBSTACLE = (40, 40, 40)
GOAL = (210, 40, 40)


class Renderer:
    """Draws world 0 of a :class:`~crowdbench.worlds.CrowdWorld` into ``size``×``size`` RGB frames.

    Pedestrians are blue, or green while responsive to the robot (ξ = 1, latent-responsive crowds); the robot is
    orange with its trail, its goal a red cross and its sensing range a thin circle.
    """

    def __init__(self, world, size: int = 480) -> None:
        self.size = size
        self.half = float(world.layout.half_size) + 0.5
        self.trail: list[np.ndarray] = []

    def clear(self) -> None:
        self.trail = []

    def record(self, world) -> None:
        """Remember the robot's position for its trail."""
        self.trail.append(world.pos[0, 0].copy())

    def _px(self, p: np.ndarray) -> tuple[float, float]:
        s = self.size / (2 * self.half)
        return (float((p[0] + self.half) * s), float((self.half - p[1]) * s))

    def frame(self, world) -> np.ndarray:
        """RGB frame ``(size, size, 3)`` uint8 of the current state."""
        img = Image.new("RGB", (self.size, self.size), (250, 250, 250))
        d = ImageDraw.Draw(img)
        s = self.size / (2 * self.half)
        for poly in world.obstacles:
            pts = [self._px(np.asarray(p)) for p in poly]
            if len(pts) == 2:
                d.line(pts, fill=OBSTACLE, width=3)
            else:
                d.polygon(pts, fill=(120, 120, 120), outline=OBSTACLE)
        rx, ry = self._px(world.pos[0, 0])
        rs = world.config.sensing_range * s
        d.ellipse([rx - rs, ry - rs, rx + rs, ry + rs], outline=(225, 225, 225))
        if len(self.trail) > 1:
            d.line([self._px(p) for p in self.trail], fill=ROBOT, width=2)
        gx, gy = self._px(world.goal[0, 0])
        d.line([gx - 6, gy - 6, gx + 6, gy + 6], fill=GOAL, width=3)
        d.line([gx - 6, gy + 6, gx + 6, gy - 6], fill=GOAL, width=3)
        xi = world.human_model.info().get("xi")
        for i in np.flatnonzero(world.active[0, 1:]):
            x, y = self._px(world.pos[0, i + 1])
            r = world.radius[0, i + 1] * s
            color = RESPONSIVE if xi is not None and xi[0, i] else HUMAN
            d.ellipse([x - r, y - r, x + r, y + r], fill=color, outline=(20, 20, 20))
            hx = x + r * np.cos(world.heading[0, i + 1])
            hy = y - r * np.sin(world.heading[0, i + 1])
            d.line([x, y, hx, hy], fill=(255, 255, 255), width=1)
        r = world.radius[0, 0] * s
        d.ellipse([rx - r, ry - r, rx + r, ry + r], fill=ROBOT, outline=(20, 20, 20))
        d.text((6, 6), f"t = {world.steps[0] * world.dt:5.2f} s", fill=(0, 0, 0))
        legend = [(ROBOT, "robot"), (HUMAN, "pedestrian"), (RESPONSIVE, "responsive (xi=1)"), (GOAL, "goal")]
        x = 6
        for color, label in legend:
            d.ellipse([x, self.size - 16, x + 9, self.size - 7], fill=color)
            d.text((x + 13, self.size - 18), label, fill=(0, 0, 0))
            x += 20 + 6 * len(label)
        return np.asarray(img, dtype=np.uint8)


def save_gif(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: float = 8.0) -> None:
    """Write RGB frames as an animated GIF, atomically (temporary file + rename)."""
    if not frames:
        raise ValueError("save_gif needs at least one frame")
    images = [Image.fromarray(f) for f in frames]
    with atomic_path(path, suffix=".gif") as tmp:
        images[0].save(tmp, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
