"""Files in and out, at the edge of the pipeline: stages hand each other objects, never files.

    files.py         atomic writes (`atomic_write`) and staged folders (`StagedFolder`)
    meshes.py        mesh files by suffix: readers (OBJ, OFF, STL, PLY, GLB, GLTF; `load_mesh`) and
                     writers (OBJ, PLY, GLB, OFF, STL; `write_mesh`)
    fold.py          FOLD 1.1: crease patterns and folding paths out, FoldTree / FoldNet in
    svg.py, pdf.py, dxf.py, png.py, sheet_style.py   sheets (`fabricate.page.Page`) as files
                     (svg.py: the print file and the cut file of a page)
    png.py           also PNG encoding (`png_bytes`) and mesh pictures
    raster.py        a small software rasteriser (previews): triangles, lines, part colours, mesh views
    segmentation.py  the files of `polyfold segment`
"""
