"""Pure, vectorised physics: each function cites its source equation.

Every function takes SI floats or NumPy arrays that broadcast against each other
(typically temperatures x samples) and returns NumPy float arrays. Temperatures are in
degC, the paper's convention. No I/O, no unit objects, no printing.
"""
