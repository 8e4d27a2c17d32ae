"""The whole job: `make` runs every stage and writes a folder a person can build from.

    make.py          `make`: a mesh (file or in memory) in, the make folder and its report out
    options.py       `MakeOptions`, paper sizes, the checks every front end runs first (light)
    parts.py         segment + unfold: the parts of the mesh and their nets; the unfold command's shares
    folding.py       a verified folding path per piece (pieces split in two when none is found)
    sheets.py        fit to the page, tabs and labels, packing (through fabricate/)
    export.py        the make folder, written through formats/ into a staged folder
    instructions.py  instructions.html
    report.py        report.json and assembly.json as dataclasses (written here, read by view and batch)
    folder.py        a make folder read back (`load_folder`), its pieces posed along their paths
    nets.py          the `unfold` command's job: nets, one FOLD document, optionally a path
"""
