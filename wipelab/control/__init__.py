"""Force control for wiping: the velocity-resolved compliance of eqs. 9-12 and the online
learning of the force profile (eqs. 13-15). Numpy, and a numba kernel for the learning's
per-sample loop.

Notation: F contact force on the tool (N, world, z up); F_0 target force; k_F force gain
(m/(N s)); z commanded TCP height (m); phi phase (rad); Omega frequency (rad/s).
"""

from wipelab.control.compliance import (FEEDBACK_MODES, ComplianceIntegrator, ComplianceParams,
                                        compliance_velocity, dead_zone, feedback_force,
                                        safety_tripped)
from wipelab.control.force_profile import (COMPARISON_PHASES, REFERENCES, ConvergenceMonitor,
                                           ForceProfileLearner, ProfileLearningParams)

__all__ = ["COMPARISON_PHASES", "FEEDBACK_MODES", "ComplianceIntegrator", "ComplianceParams",
           "ConvergenceMonitor", "ForceProfileLearner", "ProfileLearningParams", "REFERENCES",
           "compliance_velocity", "dead_zone", "feedback_force", "safety_tripped"]
