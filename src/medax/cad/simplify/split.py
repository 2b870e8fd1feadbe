"""Split every fillet along its medial curve with one ``BRepAlgoAPI_Splitter`` call.

The solid is the argument, all medial edges the tools. The result's faces are traced back to
the original faces through the splitter's history.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from OCP.BRepAlgoAPI import BRepAlgoAPI_Splitter
from OCP.collections import List_TopoDS_Shape
from OCP.TopAbs import TopAbs_FACE

from medax.cad.simplify.occ import shape_map, small_list
from medax.errors import CadError


@dataclass(frozen=True)
class SplitResult:
    """The split solid ``shape``, its face map, and ``origin[k]``: the original face index
    (0-based) of result face ``k`` (0-based)."""

    shape: Any
    face_map: Any
    origin: tuple[int, ...]

    def pieces(self, face: int) -> list[int]:
        """Result faces coming from original face ``face``."""
        return [k for k, o in enumerate(self.origin) if o == face]


def split_along(shape: Any, tools: Sequence[Any], fuzzy: float = 0.0) -> SplitResult:
    """Split ``shape`` by the edges ``tools``; raises :class:`CadError` when OCCT fails."""
    if not tools:  # nothing to split (every fillet merged whole): the shape as it is
        fmap = shape_map(shape, TopAbs_FACE)
        return SplitResult(shape, fmap, tuple(range(fmap.Size())))
    args = List_TopoDS_Shape()
    args.Append(shape)
    tl = List_TopoDS_Shape()
    for t in tools:
        tl.Append(t)
    sp = BRepAlgoAPI_Splitter()
    sp.SetArguments(args)
    sp.SetTools(tl)
    if fuzzy > 0:
        sp.SetFuzzyValue(fuzzy)
    sp.Build()
    if not sp.IsDone():
        raise CadError("splitting the fillets along their medial curves failed (OCCT splitter)")
    result, reshape = _without_internal_edges(sp.Shape())
    rmap = shape_map(result, TopAbs_FACE)
    omap = shape_map(shape, TopAbs_FACE)
    origin = [-1] * rmap.Size()
    for i in range(1, omap.Size() + 1):
        f = omap.FindKey(i)
        mods = sp.Modified(f)
        targets = small_list(mods) if mods.Size() > 0 else [f]
        for g in targets:
            k = rmap.FindIndex(reshape.Value(g) if reshape is not None else g)
            if k > 0:
                origin[k - 1] = i - 1
    if min(origin) < 0:
        raise CadError("splitter history lost a face (cannot trace pieces to their faces)")
    return SplitResult(result, rmap, tuple(origin))


def _without_internal_edges(shape: Any) -> tuple[Any, Any | None]:
    """``shape`` without the edges lying inside a face (INTERNAL): where a medial tool
    edge's overshoot runs on into a neighbouring blend that continues the fillet's surface,
    the splitter embeds it there; it bounds nothing. Returns the shape and the
    ``BRepTools_ReShape`` that removed them (None when there were none)."""
    from OCP.BRepTools import BRepTools_ReShape
    from OCP.TopAbs import TopAbs_INTERNAL

    from medax.cad.simplify.occ import edges_of, faces_of

    inner = [e for f in faces_of(shape) for e in edges_of(f) if e.Orientation() == TopAbs_INTERNAL]
    if not inner:
        return shape, None
    reshape = BRepTools_ReShape()
    for e in inner:
        reshape.Remove(e)
    return reshape.Apply(shape), reshape
