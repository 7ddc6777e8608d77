"""FrameTree: the robot's coordinate frames as a tree of transforms, looked up as tf2 does.

Every frame has at most one parent. ``set(parent, child, T_parent_child, stamp_ns)``
replaces the child's transform (the newest by stamp wins; a static one never ages), and
``lookup(target, source)`` returns ``T_target_source``, the pose of ``source`` in
``target`` (it maps a point given in ``source`` into ``target``), chained through their
common ancestor. Only the latest transforms are kept: a lookup is tf2's
``lookup_transform(target, source, Time())`` ("the latest available"), with the stamp of
the oldest dynamic transform on the path, so the caller can judge its age.

No ROS here: :mod:`rm_base.plugin.frames` sets the plugins' transforms and sends them on /tf.
"""

from __future__ import annotations

import dataclasses
import threading

from rm_base.errors import InputRejectedError
from rm_base.geometry.transforms import SE3


class FrameLookupError(InputRejectedError):
    """A lookup between frames that are unknown or not connected."""


@dataclasses.dataclass(frozen=True)
class FrameLink:
    """One edge of the tree: the child's pose in its parent.

    Attributes:
        parent: parent frame id.
        transform: ``T_parent_child``.
        stamp_ns: when it was true [ns] (0 for a static transform).
        static: never ages (/tf_static).
    """

    parent: str
    transform: SE3
    stamp_ns: int
    static: bool


@dataclasses.dataclass(frozen=True)
class FrameLookup:
    """The answer to a lookup.

    Attributes:
        transform: ``T_target_source``.
        stamp_ns: stamp of the oldest dynamic transform on the path; None if all were
            static (or source is target).
    """

    transform: SE3
    stamp_ns: int | None


class FrameTree:
    """The latest transform of every frame to its parent; thread-safe."""

    def __init__(self) -> None:
        self._links: dict[str, FrameLink] = {}
        self._lock = threading.Lock()

    def set(
        self, parent: str, child: str, transform: SE3, stamp_ns: int, *, static: bool = False
    ) -> bool:
        """Set child's pose in parent (``T_parent_child``); return whether it was taken.

        An older stamp than the one held for child is ignored (False), as tf2 keeps the
        newest.

        Raises:
            InputRejectedError: an empty frame id, a frame its own parent, or a parent that
                would close a loop (child is among the parent's ancestors).
        """
        parent, child = parent.lstrip('/'), child.lstrip('/')
        if not parent or not child:
            raise InputRejectedError(f'frame ids must not be empty, got {parent!r} -> {child!r}')
        if parent == child:
            raise InputRejectedError(f'frame {child!r} cannot be its own parent')
        with self._lock:
            held = self._links.get(child)
            if held is not None and not static and not held.static and stamp_ns < held.stamp_ns:
                return False
            if child in self._ancestors(parent):
                raise InputRejectedError(
                    f'{parent!r} -> {child!r} would close a loop: {child!r} is an ancestor '
                    f'of {parent!r}'
                )
            self._links[child] = FrameLink(parent, transform, 0 if static else stamp_ns, static)
        return True

    def frames(self) -> frozenset[str]:
        """Every frame id the tree knows (parents and children)."""
        with self._lock:
            return frozenset(self._links) | {link.parent for link in self._links.values()}

    def parent(self, frame: str) -> FrameLink | None:
        """The link of frame to its parent, or None for a root or an unknown frame."""
        with self._lock:
            return self._links.get(frame.lstrip('/'))

    def lookup(self, target: str, source: str) -> FrameLookup:
        """``T_target_source``: maps a point given in source into target.

        Raises:
            FrameLookupError: a frame is unknown, or the two are in different trees.
        """
        target, source = target.lstrip('/'), source.lstrip('/')
        with self._lock:
            if target == source:
                return FrameLookup(SE3.identity(), None)
            known = set(self._links) | {link.parent for link in self._links.values()}
            for frame in (target, source):
                if frame not in known:
                    raise FrameLookupError(
                        f'unknown frame {frame!r} (known: {", ".join(sorted(known))})'
                    )
            up_source = self._chain(source)
            up_target = self._chain(target)
            frames_of_target = [frame for frame, _ in up_target]
            common = next((f for f, _ in up_source if f in frames_of_target), None)
            if common is None:
                raise FrameLookupError(
                    f'frames {target!r} and {source!r} are not connected (their roots: '
                    f'{up_target[-1][0]!r}, {up_source[-1][0]!r})'
                )
            stamps: list[int] = []
            t_common_source = self._compose(up_source, common, stamps)
            t_common_target = self._compose(up_target, common, stamps)
        return FrameLookup(t_common_target.inverse() @ t_common_source, min(stamps, default=None))

    # Caller holds self._lock for the helpers below.

    def _ancestors(self, frame: str) -> list[str]:
        return [f for f, _ in self._chain(frame)]

    def _chain(self, frame: str) -> list[tuple[str, FrameLink | None]]:
        """[(frame, its link), (its parent, its link), ..., (root, None)]."""
        chain: list[tuple[str, FrameLink | None]] = []
        while True:
            link = self._links.get(frame)
            chain.append((frame, link))
            if link is None:
                return chain
            frame = link.parent

    @staticmethod
    def _compose(
        chain: list[tuple[str, FrameLink | None]], ancestor: str, stamps: list[int]
    ) -> SE3:
        """``T_ancestor_first`` along chain; appends the dynamic links' stamps."""
        transform = SE3.identity()
        for frame, link in chain:
            if frame == ancestor:
                return transform
            assert link is not None  # the ancestor is on the chain, above this frame
            transform = link.transform @ transform
            if not link.static:
                stamps.append(link.stamp_ns)
        return transform
