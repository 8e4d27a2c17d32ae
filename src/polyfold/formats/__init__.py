"""Files in and out, at the edge of the pipeline: stages hand each other objects, never files.

    files.py         atomic writes
    meshes.py        mesh files in (OBJ, OFF, STL, PLY, GLB, GLTF) and OBJ out; `load_mesh`
    fold.py          FOLD 1.1 nets and folding paths
    svg.py, pdf.py, dxf.py, png.py, sheet_style.py   sheets (`fabricate.page.Page`) as files
    png.py           also PNG encoding (`png_bytes`) and mesh pictures
    raster.py        a small software rasteriser (previews): triangles, lines, part colours, mesh views
    segmentation.py  the files of `polyfold segment`
"""
