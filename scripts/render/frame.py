# Render one frame of a drape run's XDMF time series with ParaView
# (pvbatch; issue 16, docs/animate.md).  It shows that DIR/drape.xmf (with
# DIR/drape.h5) opens in ParaView as a time series and what the cloth looks
# like at that time.  ParaView is not a dependency of drape: install it
# (Debian: paraview, xvfb) to use this script.
#   xvfb-run -a pvbatch scripts/render/frame.py DIR/drape.xmf TIME OUT.png [TITLE]
import sys

from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, Render,
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
view.ViewSize = [1200, 900]
view.Background = [1.0, 1.0, 1.0]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.OrientationAxesVisibility = 0
d = Show(reader, view)
d.Representation = "Surface With Edges"
d.AmbientColor = d.DiffuseColor = [0.80, 0.62, 0.45]
d.EdgeColor = [0.35, 0.25, 0.18]
d.Specular = 0.2
view.CameraPosition = [1.6, -2.4, 0.9]
view.CameraFocalPoint = [0.0, 0.0, -0.35]
view.CameraViewUp = [0.0, 0.0, 1.0]
ResetCamera()
label = Text(Text="%s t = %.3f s (%d frames in the file)" % (title, near, len(times)))
ld = Show(label, view)
ld.Color = [0.1, 0.1, 0.1]
ld.FontSize = 14
Render()
SaveScreenshot(png, view, ImageResolution=[1200, 900])
print("rendered t = %.4f s of %d time steps into %s" % (near, len(times), png))
