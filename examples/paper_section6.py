# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # The paper's worked example (section 6) with the notebook API
#
# *Eddy Current Damper Simulation and Modeling* (CDA InterCorp), section 6: a Cc-16 eddy
# current damper behind a 380:1 gearbox on a spring-loaded test hinge, deployed in a
# temperature chamber at -40, +25 and +100 degC. The config `paper_cc16.toml` holds the
# paper's constants; this notebook recomputes the section's numbers and the simulation
# curves of its Fig. 4-6 with `ecdsim.deploy` (docs/api.md).
#
# The paper's figures also show measured positions; those measurements are not
# published as data, so only the simulation curves are reproduced here.
#
# This file is the source (jupytext percent format); `paper_section6.ipynb` is the same
# notebook executed. `tests/test_notebook.py` runs this file as a notebook on every test
# run and checks that the `.ipynb` holds the same code.

# %%
# %matplotlib inline
import pint
from IPython.display import display

import ecdsim

result = ecdsim.deploy("paper_cc16.toml")
result

# %% [markdown]
# ## The ECD reflected to the slow shaft (Eq. 1-4)
#
# The paper quotes, at +25 degC, FECD25 = 0.52 N·m and BECD25 = 24 N·m·s/rad (two
# figures). The long-format table has one row per temperature and method, with the units
# in the column names:

# %%
frame = result.to_dataframe()
at25 = frame[(frame.temperature_C == 25.0) & (frame.method == "exact")].iloc[0]
print(f"BECD25 = {at25.damping_rate_Nms_per_rad:.2f} N*m*s/rad (paper: 24)")
print(f"FECD25 = {at25.friction_Nm:.3f} N*m (paper: 0.52)")
assert abs(at25.damping_rate_Nms_per_rad / 24.0 - 1.0) < 0.02  # the paper's 2 figures
assert abs(at25.friction_Nm / 0.52 - 1.0) < 0.03
frame[
    [
        "temperature_C",
        "method",
        "damping_rate_Nms_per_rad",
        "friction_Nm",
        "system_friction_Nm",
        "deployment_time_s",
        "start_speed_rad_s",
        "end_speed_rad_s",
    ]
]

# %% [markdown]
# ## Fig. 4-6: position against time at +25, -40 and +100 degC
#
# One figure per temperature, in the paper's order. "paper" is the paper's method
# (Eq. 8-13: constant deceleration between the start and end speeds); "exact" solves
# the same quasi-static equation exactly (the speed falls exponentially, so the end of
# travel comes later).

# %%
for temperature in (25, -40, 100):
    figures = ecdsim.deploy("paper_cc16.toml", temperatures=temperature).plot()
    display(figures[0])  # angle against time

# %% [markdown]
# ## Units
#
# Inputs may be pint quantities or plain SI numbers (temperatures in degC). The same
# hinge at 77 degF, with the spring's start torque given in lbf·in:

# %%
ureg = pint.UnitRegistry()
us = ecdsim.deploy(
    "paper_cc16.toml",
    temperatures=ureg.Quantity(77.0, "degF"),
    methods="paper",
    overrides={"load.start_torque": ureg.Quantity(33.0, "lbf*inch")},
)
us.to_dataframe()[["temperature_C", "method", "deployment_time_s"]]

# %% [markdown]
# ## All three temperatures on one plot, and the ECD torque against speed

# %%
figures = result.plot()
for figure in figures:
    display(figure)
