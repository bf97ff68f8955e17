"""Opens a Sluice run in ParaView: the particles and the walls of its XDMF index.

Fluid particles (kinds 0 and 2: fluid and open-boundary fluid) are shown as
points coloured by the magnitude of `velocity`, wall particles (kind 1) in
grey, the scene's walls (<prefix>_walls.h5: segments in 2D, triangles in 3D,
moving walls at every snapshot) as dark lines or surfaces, with the time in
a corner.

    pvpython tools/paraview/open_run.py RUN                    # interactive window
    pvpython tools/paraview/open_run.py RUN --png out.png --time 1.0
    pvpython tools/paraview/open_run.py RUN --state run.pvsm   # for `paraview --state=run.pvsm`

RUN is the run's output directory (`sluice run SCENE --out RUN`). With --png
the picture is rendered off screen (pvbatch, or pvpython under xvfb-run
where there is no display: docs/paraview.md). Needs ParaView's Python
(tested with 5.11, Debian 12: apt-get install paraview python3-paraview).
"""

import argparse
import os
import re
import sys


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Open a Sluice run (particles and walls) in ParaView.")
    parser.add_argument("run", help="the run's output directory")
    parser.add_argument("--prefix", default="particles",
                        help="the hdf5 writer's prefix (default: particles)")
    parser.add_argument("--png", help="render a picture to this PNG file and exit")
    parser.add_argument("--state", help="save a ParaView state file (.pvsm) and exit")
    parser.add_argument("--time", type=float,
                        help="simulated time to show, s (default: the last snapshot)")
    parser.add_argument("--size", type=int, nargs=2, default=[1600, 600],
                        metavar=("WIDTH", "HEIGHT"), help="picture size in pixels")
    parser.add_argument("--range", type=float, nargs=2, metavar=("MIN", "MAX"),
                        help="velocity colour range, m/s (default: the shown snapshot's)")
    parser.add_argument("--fit", choices=["fluid", "all"],
                        help="frame the fluid particles or everything, walls included (default: "
                             "the fluid in 2D, everything in 3D)")
    parser.add_argument("--wall-particles", choices=["show", "hide"],
                        help="wall particles (kind 1) in grey or hidden (default: shown in 2D, "
                             "hidden in 3D, where the walls' surfaces show the walls)")
    parser.add_argument("--point-size", type=float,
                        help="particle size in pixels (default: about the particle spacing in "
                             "2D, 3 in 3D)")
    return parser.parse_args(argv)


def particle_spacing(run):
    """particles.spacing from RUN/scene.resolved.yaml (m), or None."""
    try:
        with open(os.path.join(run, "scene.resolved.yaml")) as scene:
            text = scene.read()
    except OSError:
        return None
    found = re.search(r"^particles:\s*\n(?:[ \t]+.*\n)*?[ \t]+spacing:\s*([0-9.eE+-]+)", text,
                      re.MULTILINE)
    return float(found.group(1)) if found else None


def threshold(source, array, association, low, high, invert=False):
    """The cells whose `array` lies in [low, high] (or outside, with invert);
    blocks without the array (particles for `wall`, walls for `kind`) give
    nothing, so this also picks the blocks."""
    from paraview import simple
    kept = simple.Threshold(Input=source)
    kept.Scalars = [association, array]
    kept.LowerThreshold = low
    kept.UpperThreshold = high
    kept.ThresholdMethod = "Between"
    kept.Invert = 1 if invert else 0
    return kept


def build(args):
    from paraview import simple

    index = os.path.join(args.run, args.prefix + ".xdmf")
    if not os.path.isfile(index):
        sys.exit("open_run.py: %s does not exist (is %s a Sluice run's output directory?)"
                 % (index, args.run))
    reader = simple.Xdmf3ReaderT(registrationName=args.prefix + ".xdmf", FileName=index)
    times = list(reader.TimestepValues) if reader.TimestepValues else [0.0]
    time = times[-1] if args.time is None else min(times, key=lambda t: abs(t - args.time))
    reader.UpdatePipeline(time)
    bounds = reader.GetDataInformation().GetBounds()
    flat = abs(bounds[5] - bounds[4]) <= 1e-12 * max(1.0, abs(bounds[1] - bounds[0]))

    simple._DisableFirstRenderCameraReset()  # keep the camera set below
    view = simple.GetActiveViewOrCreate("RenderView")
    view.ViewSize = list(args.size)
    view.Background = [1.0, 1.0, 1.0]
    try:  # ParaView 5.10+: the palette would override the background
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    view.OrientationAxesVisibility = 0

    fluid = threshold(reader, "kind", "POINTS", 1, 1, invert=True)
    simple.RenameSource("fluid", fluid)
    shown = fluid_shown = simple.Show(fluid, view)
    shown.SetRepresentationType("Points")
    shown.PointSize = args.point_size or 3.0
    shown.RenderPointsAsSpheres = 1
    simple.ColorBy(shown, ("POINTS", "velocity", "Magnitude"))
    lut = simple.GetColorTransferFunction("velocity")
    lut.ApplyPreset("Turbo", True) or lut.ApplyPreset("Jet", True)
    if args.range:
        lut.RescaleTransferFunction(args.range[0], args.range[1])
        lut.AutomaticRescaleRangeMode = "Never"
    bar = simple.GetScalarBar(lut, view)
    bar.Title = "|velocity| (m/s)"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.WindowLocation = "Upper Right Corner"
    shown.SetScalarBarVisibility(view, True)

    wall_particles = threshold(reader, "kind", "POINTS", 1, 1)
    simple.RenameSource("wall particles", wall_particles)
    shown = walls_shown = simple.Show(wall_particles, view)
    shown.SetRepresentationType("Points")
    shown.PointSize = max(1.0, (args.point_size or 3.0) - 1)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = shown.DiffuseColor = [0.6, 0.6, 0.6]
    show_wall_particles = flat if args.wall_particles is None else args.wall_particles == "show"
    if not show_wall_particles:
        simple.Hide(wall_particles, view)

    walls = threshold(reader, "wall", "CELLS", 0, 1e9)
    simple.RenameSource("walls", walls)
    shown = simple.Show(walls, view)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = shown.DiffuseColor = [0.15, 0.15, 0.15]
    if flat:
        shown.SetRepresentationType("Wireframe")
        shown.LineWidth = 3.0
    else:
        shown.SetRepresentationType("Surface")
        shown.Opacity = 0.35

    annotation = simple.AnnotateTimeFilter(Input=reader)
    annotation.Format = "t = {time:.3f} s"
    simple.RenameSource("time", annotation)
    shown = simple.Show(annotation, view)
    shown.WindowLocation = "Upper Center"
    shown.FontSize = 24
    shown.Color = [0.0, 0.0, 0.0]

    simple.Hide(reader, view)
    scene = simple.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = time
    view.ViewTime = time
    if not args.range:  # the shown snapshot's range
        fluid.UpdatePipeline(time)
        fluid_shown.RescaleTransferFunctionToDataRange(False, True)
    if flat:
        view.InteractionMode = "2D"
        view.CameraParallelProjection = 1
        view.CameraPosition = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 1.0]
        view.CameraFocalPoint = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]
    else:
        # from the front (-y), a little to the right and above; z is up
        centre = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
                  0.5 * (bounds[4] + bounds[5])]
        reach = 2.0 * max(bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4])
        view.CameraFocalPoint = centre
        view.CameraPosition = [centre[0] + 0.35 * reach, centre[1] - reach,
                               centre[2] + 0.45 * reach]
        view.CameraViewUp = [0.0, 0.0, 1.0]
    if (args.fit or ("fluid" if flat else "all")) == "fluid":
        fluid.UpdatePipeline(time)
        box = fluid.GetDataInformation().GetBounds()
        if box[0] <= box[1]:
            pad = 0.05 * max(box[1] - box[0], box[3] - box[2], box[5] - box[4])
            box = [box[0] - pad, box[1] + pad, box[2] - pad, box[3] + pad, box[4] - pad,
                   box[5] + pad]
            view.ResetCamera(False)
            if flat:  # the parallel scale is half the height shown
                centre = [0.5 * (box[0] + box[1]), 0.5 * (box[2] + box[3])]
                view.CameraFocalPoint = [centre[0], centre[1], 0.0]
                view.CameraPosition = [centre[0], centre[1], view.CameraPosition[2]]
                aspect = float(args.size[0]) / float(args.size[1])
                view.CameraParallelScale = max(0.5 * (box[3] - box[2]),
                                               0.5 * (box[1] - box[0]) / aspect)
                spacing = particle_spacing(args.run)
                if args.point_size is None and spacing:
                    pixels = spacing * args.size[1] / (2 * view.CameraParallelScale)
                    fluid_shown.PointSize = max(2.0, 0.8 * pixels)
                    walls_shown.PointSize = max(1.0, 0.6 * pixels)
            else:
                view.ResetCamera(box[0], box[1], box[2], box[3], box[4], box[5])
        else:
            view.ResetCamera(False)
    else:
        view.ResetCamera(False)
    simple.Render(view)
    return view, time


def main(argv):
    args = parse_arguments(argv)
    try:
        from paraview import simple
    except ImportError:
        sys.exit("open_run.py: run it with ParaView's Python: pvpython or pvbatch "
                 "(Debian: apt-get install paraview python3-paraview)")
    view, time = build(args)
    if args.state:
        simple.SaveState(args.state)
        print("open_run.py: state saved to %s (paraview --state=%s)" % (args.state, args.state))
    if args.png:
        simple.SaveScreenshot(args.png, view, ImageResolution=list(args.size),
                              TransparentBackground=0)
        print("open_run.py: t = %.6g s rendered to %s" % (time, args.png))
    if not args.state and not args.png:
        simple.Interact(view)


if __name__ == "__main__":
    main(sys.argv[1:])
