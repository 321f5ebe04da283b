"""Exports of the friction model to simulators (FMU, MATLAB, Modelica, Simscape, Hopsan)."""
