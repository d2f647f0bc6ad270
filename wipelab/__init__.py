"""wipelab: teach a humanoid to wipe surfaces from a human demonstration.

After Gams, Do, Ude, Asfour, Dillmann, "On-line periodic movement and force-profile
learning for adaptation to new surfaces", Humanoids 2010.

Stages: ``track`` (stereo video -> 3D sponge trajectory), ``learn`` (two-layer periodic
imitation: adaptive oscillators + periodic DMP), ``adapt`` (force-profile learning on the
simulated ARMAR-IIIb), ``replay`` (the adapted movement at any frequency).
"""

__version__ = "0.1.0"
