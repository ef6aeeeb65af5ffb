"""The named choices of wbsa's settings, declared once as ``Literal`` types.

Every stage's settings dataclass annotates its choice fields with these types; the tuples of
valid values (for argparse ``choices``, messages and checks) are derived from them with
:func:`typing.get_args`, so a choice is added in one place.
"""

from __future__ import annotations

from typing import Literal, get_args

#: How a population is made: ``random`` (paper: Virtual Random), ``survey`` (paper: Virtual NHANES),
#: ``table`` (phenotypes read from a file).
PopulationKind = Literal["random", "survey", "table"]
#: Depth noise of the simulated sensor: none, Kinect v1's (Nguyen et al. 2012, the paper's), or the camera's own
#: technology's (:data:`wbsa.sensor.technology.TECHNOLOGIES`).
NoiseModel = Literal["none", "nguyen2012", "camera"]
#: Surface reconstruction methods (each adds a ``vbsa_recon_<method>_m2`` column).
ReconstructionMethod = Literal["grid", "ball-pivoting", "poisson"]
#: Depth-image filters applied before reconstruction.
DenoiseMethod = Literal["quadratic", "none", "bilateral", "median"]
#: Boundary skirts of the ``grid`` reconstruction.
BoundaryModel = Literal["none", "footprint", "contour"]
#: Point smoothing of the point-cloud reconstructions.
SmoothingMethod = Literal["none", "mls"]
#: Regression model kinds of the fit.
ModelKind = Literal["linear", "quadratic", "loglog", "wls"]
#: Subject groups, in report order.
GroupName = Literal["all", "males", "females", "kids", "adults", "small", "normal", "big", "obese", "underweight",
                    "tall"]
#: How a body's density is set: one constant, or from its fat fraction (Deurenberg 1991 + Siri or Brozek).
DensityModel = Literal["constant", "deurenberg-siri", "deurenberg-brozek"]
#: How a random population's body parameters are drawn: the paper's, or varied shapes (docs/population.md).
Sampling = Literal["paper", "varied"]
#: Which NHANES measures the survey matcher fits: all seven (stature, mass, waist, hip, arm circumference,
#: upper arm and upper leg length) or the first four.
SurveyMeasures = Literal["seven", "four"]
#: Ray-casting back ends (:mod:`wbsa.camera.backends`); ``auto`` picks Warp on CUDA when there is a GPU.
RaycastBackend = Literal["auto", "open3d", "warp"]
#: A named standing posture (:data:`wbsa.bodies.posture.POSTURES` has one entry per name, in this order).
PostureName = Literal["a-pose", "arms-down", "arms-wide", "hands-on-hips", "elbows-bent", "feet-together",
                      "feet-apart"]
#: What a camera returns for a pixel straddling a depth edge (:mod:`wbsa.sensor.depth_edges`): the render's
#: depth, a mix of the two surfaces (time-of-flight), or nothing (the camera's own flying-pixel filter).
EdgePixels = Literal["kept", "mixed", "dropped"]
#: What surrounds the subject in a held-out test capture: a room (floor, wall, maybe a second person), or
#: nothing (a render of the body alone, as of a 3-D body scan).
TestScene = Literal["room", "alone"]
#: Who draws a held-out capture: the project's renderer (scan engine and sensor model), the plain one
#: (:mod:`wbsa.testing.plain_render`: Open3D and its own noise), or both, side by side.
TestRenderer = Literal["project", "plain", "both"]
#: Units and up axis of a mesh file (:func:`wbsa.simulate.target.to_body_frame`).
MeshUnits = Literal["m", "cm", "mm", "in"]
MeshUp = Literal["z", "y"]
#: Camera presets (:data:`wbsa.camera.presets.CAMERAS` has one record per name, in this order).
PresetName = Literal["kinect-v1", "kinect-v2", "tum", "azure-kinect-nfov", "azure-kinect-wfov", "realsense-d435",
                     "realsense-d455", "phone-lidar"]
#: How a depth camera measures: its depth noise and quantisation follow (:mod:`wbsa.camera.presets`).
DepthTechnology = Literal["structured-light", "time-of-flight", "active-stereo", "lidar"]
#: Estimation routes of ``wbsa estimate`` (:mod:`wbsa.estimation.methods`): the regression on the image's
#: measures, the whole body fitted to the view, or both side by side.
Method = Literal["regression", "body-fit", "both"]
#: A population's ``posture`` setting: a posture name, or ``mixed`` (a random name per subject).
PostureChoice = Literal[Literal["a-pose", "mixed"], PostureName]
#: How the estimator picks the subject among several people (besides an (x, y) pixel of it).
PickRule = Literal["nearest", "largest", "center"]
#: Robust penalty of the body fit's point-to-surface residuals (:mod:`wbsa.estimation.methods.body_fit.objective`).
RobustLoss = Literal["geman-mcclure", "huber"]
#: The body fit's data term (:mod:`wbsa.estimation.methods.body_fit.objective`): depth compared along each camera ray,
#: or each point against its closest model surface point.
DataTerm = Literal["along-ray", "closest-point"]

POPULATION_KINDS: tuple[str, ...] = get_args(PopulationKind)
NOISE_MODELS: tuple[str, ...] = get_args(NoiseModel)
RECONSTRUCTION_METHODS: tuple[str, ...] = get_args(ReconstructionMethod)
DENOISE_METHODS: tuple[str, ...] = get_args(DenoiseMethod)
BOUNDARY_MODELS: tuple[str, ...] = get_args(BoundaryModel)
SMOOTHING_METHODS: tuple[str, ...] = get_args(SmoothingMethod)
MODEL_KINDS: tuple[str, ...] = get_args(ModelKind)
GROUP_NAMES: tuple[str, ...] = get_args(GroupName)
DENSITY_MODELS: tuple[str, ...] = get_args(DensityModel)
SAMPLINGS: tuple[str, ...] = get_args(Sampling)
SURVEY_MEASURES: tuple[str, ...] = get_args(SurveyMeasures)
RAYCAST_BACKENDS: tuple[str, ...] = get_args(RaycastBackend)
POSTURE_NAMES: tuple[str, ...] = get_args(PostureName)
POSTURE_CHOICES: tuple[str, ...] = get_args(PostureChoice)
EDGE_PIXELS: tuple[str, ...] = get_args(EdgePixels)
TEST_SCENES: tuple[str, ...] = get_args(TestScene)
TEST_RENDERERS: tuple[str, ...] = get_args(TestRenderer)
PRESET_NAMES: tuple[str, ...] = get_args(PresetName)
DEPTH_TECHNOLOGIES: tuple[str, ...] = get_args(DepthTechnology)
METHODS: tuple[str, ...] = get_args(Method)
MESH_UNITS: tuple[str, ...] = get_args(MeshUnits)
MESH_UPS: tuple[str, ...] = get_args(MeshUp)
ROBUST_LOSSES: tuple[str, ...] = get_args(RobustLoss)
DATA_TERMS: tuple[str, ...] = get_args(DataTerm)
PICK_RULES: tuple[str, ...] = get_args(PickRule)
