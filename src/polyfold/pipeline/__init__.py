"""The whole job: `make` runs every stage and writes a folder a person can build from.

    make.py       `make` (mesh in, sheets, FOLD files, instructions and report out)
"""
