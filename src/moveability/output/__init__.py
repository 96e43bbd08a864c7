"""What a person sees: figures of the workspace, joint space, regions and
motions (:mod:`.plot`, 2-D; :mod:`.plot3d`, slices and solids of 3-dof
regions), VTK files for ParaView (:mod:`.vtk`) and the HTML report
(:mod:`.report`). matplotlib is imported when a figure is drawn.
"""
