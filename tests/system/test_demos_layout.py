"""The layout design demo (issue 52 item 5): a PneuNet's stiff layer designed for a 120 degree curl, checked by a
plain static run of the written layout.msh (the two materials by volume group, a model built afresh from the file:
none of the design's machinery) and against the same actuator all soft."""
from system.demo_runs import NUMBER, demo, grab  # noqa: F401 (demo: fixture)


def test_pneunet_layout_demo(demo):
    """The written layout, re-solved by a plain static scene, curls within 1 degree of the 120 degree target (the
    issue's tolerance), and as the design's own cast solve said (to 0.01 degree: the same equilibrium reached along
    the load steps from rest instead of from the last layout's); all soft the actuator falls short by more than 10
    degrees (the layer does the work: 95.2 degrees measured); the hard silicone within its bound of half the base."""
    out, folder = demo("pneunet_layout")
    cast, = grab(rf"the cast layout curls ({NUMBER}) deg \(target 120 deg\)", out)
    layout, = grab(rf"re-solved as a plain static scene of layout.msh: ({NUMBER}) deg", out)
    soft, = grab(rf"all in the soft silicone: ({NUMBER}) deg", out)
    fraction, = grab(rf"hard silicone in ({NUMBER})% of the base \(bound 50%\)", out)
    assert abs(layout - 120.0) < 1.0, layout
    assert abs(layout - cast) < 0.01, (layout, cast)
    assert soft < 110.0, soft
    assert 0.0 < fraction <= 50.0 + 2.0
    for name in ("placed.stl", "body.stl", "layout.png", "layout.msh"):
        assert (folder / "design" / name).stat().st_size > 0
