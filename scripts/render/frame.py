# Render one frame of a drape run's XDMF time series with ParaView
# (pvbatch; issue 16, docs/animate.md).  It shows that DIR/drape.xmf (with
# DIR/drape.h5) opens in ParaView as a time series and what the cloth looks
# like at that time.  ParaView is not a dependency of drape: install it
# (Debian: paraview, xvfb) to use this script.
#   xvfb-run -a pvbatch scripts/render/frame.py DIR/drape.xmf TIME OUT.png [TITLE]
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, Render,
                             ResetCamera, SaveScreenshot, Show, Text, XDMFReader)

xmf, t, png = sys.argv[1], float(sys.argv[2]), sys.argv[3]
title = sys.argv[4] if len(sys.argv) > 4 else ""
reader = XDMFReader(FileNames=[xmf])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues) if reader.TimestepValues else [0.0]
near = min(times, key=lambda x: abs(x - t))
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = near
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [800, 600]
view.Background = [1.0, 1.0, 1.0]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.OrientationAxesVisibility = 0
d = Show(reader, view)
ColorBy(d, None)                   # one cloth colour, not a data array
d.Representation = "Surface"
d.AmbientColor = d.DiffuseColor = [0.85, 0.68, 0.50]
d.Specular = 0.3
d.Interpolation = "Gouraud"
# a three-quarter view from the front, slightly above
b = reader.GetDataInformation().GetBounds()
c = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
r = max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
view.CameraFocalPoint = c
view.CameraPosition = [c[0] + 1.2 * r, c[1] - 2.0 * r, c[2] + 0.6 * r]
view.CameraViewUp = [0.0, 0.0, 1.0]
ResetCamera()
label = Text(Text="%s t = %.3f s (%d frames in the file)" % (title, near, len(times)))
ld = Show(label, view)
ld.Color = [0.1, 0.1, 0.1]
ld.FontSize = 14
Render()
SaveScreenshot(png, view, ImageResolution=[800, 600])
print("rendered t = %.4f s of %d time steps into %s" % (near, len(times), png))
