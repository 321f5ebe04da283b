"""Friction models that the export tests (FMU, MATLAB) share: every pressure law, every
operating-pressure rule and a reduced law."""

from cylfric.model import FrictionModel

MODELS = {
    # thesis eq. 4.1-4.3 (linear laws, mean of the chamber pressures)
    "thesis": FrictionModel(),
    # every pressure law and the "max" rule; sigma_0 itself pressure-dependent
    "mixed_laws": FrictionModel(
        {
            "F_c": {"law": "quadratic", "intercept": 60.0, "slope": 4e-6, "curvature": 1e-13},
            "F_s": {"law": "exponential", "intercept": 100.0, "amplitude": 30.0, "rate": 1e-7},
            "sigma_2": {"law": "constant", "intercept": 300.0},
            "v_r": 0.008,
            "alpha": 1.3,
        },
        reference="max",
        sigma_0={"intercept": 8e5, "slope": 0.01},
        sigma_1=900.0,
        validity={
            "pressure_min": 10e5,
            "pressure_max": 150e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.1,
        },
    ),
    # a reduced law: F_s, v_r, alpha not identified (F_s = F_c in the FMU, as in params_at)
    "coulomb_viscous": FrictionModel(
        {
            "F_c": {"intercept": 80.0, "slope": 5e-6},
            "F_s": None,
            "sigma_2": {"intercept": 350.0, "slope": 1e-6},
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb_viscous",
        reference="sum",
    ),
}
