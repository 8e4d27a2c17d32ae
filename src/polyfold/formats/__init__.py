"""Files in and out, at the edge of the pipeline: stages hand each other objects, never files.

    files.py         atomic writes
    meshes.py        mesh files in (OBJ, OFF, STL, PLY, GLB, GLTF) and OBJ out; `load_mesh`
    fold.py          FOLD 1.1 nets and folding paths
    svg.py, pdf.py, dxf.py, sheet_style.py   sheets (`fabricate.page.Page`) as files
    raster.py        PNG encoding and a small software rasteriser (previews)
    segmentation.py  the files of `polyfold segment`
"""
