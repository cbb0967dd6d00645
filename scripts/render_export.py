#!/usr/bin/python3
"""Renders an `unjam export --format vtk --probe K` file with VTK, as ParaView would show it:
left, the grains and the force chains (contact lines coloured by fn / F0); right, the probe's
displacement field u / g as arrows, the probed contact in black. The picture in docs/packing-format.md ("Exports") is made
by this script. VTK renders through an X server; on a machine without a display run it
under Xvfb (Debian xvfb):

    xvfb-run -a /usr/bin/python3 scripts/render_export.py DIR/probe-K.vtp out.png
"""
import argparse

import vtk


def read(path):
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        raise SystemExit(f"{path}: not a readable VTK PolyData file")
    return reader.GetOutput()


def plain_actor(port, color):
    """An actor of one colour for the output of a filter."""
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(port)
    mapper.ScalarVisibilityOff()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(*color)
    return actor


def grains(poly):
    """Disks of the grains (not the periodic images) as outlines, radius from the 'radius' array."""
    real = vtk.vtkThresholdPoints()
    real.SetInputData(poly)
    real.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, "image")
    real.ThresholdByLower(0.5)
    real.Update()
    real.GetOutput().GetPointData().SetActiveScalars("radius")
    circle = vtk.vtkRegularPolygonSource()
    circle.SetNumberOfSides(48)
    circle.SetRadius(1.0)
    circle.GeneratePolygonOff()
    glyph = vtk.vtkGlyph3D()
    glyph.SetInputData(real.GetOutput())
    glyph.SetSourceConnection(circle.GetOutputPort())
    glyph.SetScaleModeToScaleByScalar()
    glyph.SetScaleFactor(1.0)
    return plain_actor(glyph.GetOutputPort(), (0.55, 0.55, 0.6)), real.GetOutput()


def force_chains(poly):
    """Contact lines with fn > 0, width 3, coloured by fn / F0."""
    poly.GetCellData().SetActiveScalars("fn_over_F0")
    lo, hi = poly.GetCellData().GetArray("fn_over_F0").GetRange()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(poly)
    mapper.SetScalarModeToUseCellData()
    mapper.SetScalarRange(0.0, hi)
    lut = vtk.vtkLookupTable()
    lut.SetHueRange(0.6, 0.0)
    lut.Build()
    mapper.SetLookupTable(lut)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetLineWidth(3.0)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("fn / F0")
    bar.SetNumberOfLabels(4)
    bar.SetVerticalTitleSeparation(12)
    bar.SetWidth(0.07)
    bar.SetHeight(0.5)
    bar.SetPosition(0.9, 0.25)
    return actor, bar


def displacement_arrows(real):
    """u / g at every grain as an arrow, its length proportional to |u| / g."""
    real.GetPointData().SetActiveVectors("displacement_over_g")
    u = real.GetPointData().GetArray("displacement_over_g")
    largest = max(u.GetRange(-1)[1], 1e-300)
    arrow = vtk.vtkArrowSource()
    glyph = vtk.vtkGlyph3D()
    glyph.SetInputData(real)
    glyph.SetSourceConnection(arrow.GetOutputPort())
    glyph.SetVectorModeToUseVector()
    glyph.SetScaleModeToScaleByVector()
    glyph.SetScaleFactor(4.0 / largest)  # the largest arrow: 4 R_max
    glyph.OrientOn()
    return plain_actor(glyph.GetOutputPort(), (0.75, 0.1, 0.1))


def probed_contact(poly, contact):
    """The probed contact's line, thick and black, where the probe opens the packing."""
    one = vtk.vtkThreshold()
    one.SetInputData(poly)
    one.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_CELLS, "contact")
    one.SetLowerThreshold(contact - 0.5)
    one.SetUpperThreshold(contact + 0.5)
    surface = vtk.vtkGeometryFilter()
    surface.SetInputConnection(one.GetOutputPort())
    actor = plain_actor(surface.GetOutputPort(), (0, 0, 0))
    actor.GetProperty().SetLineWidth(6.0)
    return actor


def cell_outline(Lx, Ly):
    box = vtk.vtkOutlineSource()
    box.SetBounds(0, Lx, 0, Ly, 0, 0)
    return plain_actor(box.GetOutputPort(), (0, 0, 0))


def title(text):
    actor = vtk.vtkTextActor()
    actor.SetInput(text)
    actor.GetTextProperty().SetFontSize(20)
    actor.GetTextProperty().SetColor(0, 0, 0)
    actor.SetPosition(10, 10)
    return actor


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("vtp", help="an export with a displacement field (unjam export --probe K)")
    ap.add_argument("png", help="output picture")
    ap.add_argument("--size", type=int, default=700, help="height of the picture in pixels")
    args = ap.parse_args()

    poly = read(args.vtp)
    fd = poly.GetFieldData()
    Lx, Ly = fd.GetArray("Lx").GetValue(0), fd.GetArray("Ly").GetValue(0)
    contact = int(fd.GetArray("probed_contact").GetValue(0))
    if poly.GetPointData().GetArray("displacement_over_g") is None:
        raise SystemExit(f"{args.vtp} has no displacement field: export it with --probe K")
    disks, real = grains(poly)
    chains, bar = force_chains(poly)

    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(2 * args.size, args.size)
    panels = [
        ([disks, chains, cell_outline(Lx, Ly), bar], "force chains (contact lines, fn / F0)"),
        ([grains(poly)[0], displacement_arrows(real), probed_contact(poly, contact),
          cell_outline(Lx, Ly)],
         f"probe of contact {contact} (black): displacement u / g"),
    ]
    for i, (actors, text) in enumerate(panels):
        renderer = vtk.vtkRenderer()
        renderer.SetViewport(0.5 * i, 0.0, 0.5 * (i + 1), 1.0)
        renderer.SetBackground(1, 1, 1)
        for a in actors:
            renderer.AddViewProp(a)
        renderer.AddViewProp(title(text))
        camera = renderer.GetActiveCamera()
        camera.ParallelProjectionOn()
        # The cell a little left of centre, room on the right for the colour bar.
        camera.SetFocalPoint(0.55 * Lx, Ly / 2, 0)
        camera.SetPosition(0.55 * Lx, Ly / 2, 10 * Lx)
        camera.SetParallelScale(0.6 * Ly)
        window.AddRenderer(renderer)
    window.Render()
    shot = vtk.vtkWindowToImageFilter()
    shot.SetInput(window)
    shot.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(args.png)
    writer.SetInputConnection(shot.GetOutputPort())
    writer.Write()
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
