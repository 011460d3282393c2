"""Refining a curved boundary without a projector keeps it faceted: MeshHierarchy.build says so."""
import warnings

import pytest

from contactmg.mesh.generators import HERTZ_ARC, hertz_projector, polar_half_disk, rectangle
from contactmg.mesh.generators_3d import box, half_ball
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.mesh.quality import curved_facet_tags


def test_refining_a_curved_boundary_without_a_projector_is_reported():
    """A half disk refined without a projector keeps its arc faceted: a warning names the arc's tag
    and how far its facets turn; with the projector, or for a polygon, nothing is said."""
    with pytest.warns(UserWarning, match=rf"the facets tagged {HERTZ_ARC} \(15.0 degrees\) approximate a curved surface"):
        MeshHierarchy.build(polar_half_disk(), 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        MeshHierarchy.build(polar_half_disk(), 2, projector=hertz_projector())
        MeshHierarchy.build(rectangle(3, 2, distort=0.2), 2)
        MeshHierarchy.build(polar_half_disk(), 1)  # nothing refined


def test_curved_tags_in_3d():
    """The sphere of a half ball turns by a few tens of degrees between facets, a box's faces not at
    all (their edges, between tags, turn by 90)."""
    assert set(curved_facet_tags(half_ball("tetra"))) == {1}
    assert curved_facet_tags(box(2, 2, 2, cell="tetra")) == {}
