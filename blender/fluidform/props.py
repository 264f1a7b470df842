# The panel's settings (per scene: one Form covers every selected object) and the add-on preferences.
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

CONTROLLERS = [
    ("adaptive", "Adaptive", "The paper's controller: adaptive weights, bond breaking, boundary correction (default)"),
    ("pbfc", "PBFC", "Position-based fluid control"),
    ("weighted", "Weighted", "PBFC with colour-field weights"),
    ("thuerey", "Thürey", "Thürey et al. 2006: attraction by fill level and velocity control"),
    ("rscf", "RSCF", "Shape control by velocity features"),
    ("lcat", "LCAT", "Density attraction with temporary particles"),
    ("none", "None", "No control: the fluid only falls"),
]

# `fluidform run --device` (docs/gpu.md): the GPU path runs the adaptive controller (or none) in Vulkan compute.
DEVICES = [
    ("cpu", "CPU", "Simulate on the CPU (the reference path; default)"),
    ("auto", "Auto", "A discrete or integrated GPU when there is one and the scene is one the GPU path does, "
                     "else the CPU"),
    ("gpu", "GPU", "Vulkan compute on the GPU (a software device where there is none); a scene the GPU path "
                   "does not do is an error"),
]


class FluidFormSettings(bpy.types.PropertyGroup):
    particle_count: IntProperty(
        name="Particles", default=10000, min=100, max=10_000_000, soft_max=200_000,
        description="About how many fluid particles (and as many control particles in the targets)")
    controller: EnumProperty(name="Controller", items=CONTROLLERS, default="adaptive",
                             description="The shape controller that holds the fluid in the targets")
    device: EnumProperty(name="Device", items=DEVICES, default="cpu",
                         description="Where the fluid is simulated (fluidform run --device)")
    duration: FloatProperty(
        name="Duration", default=0.0, min=0.0, max=100_000.0, soft_max=60.0, unit="TIME_ABSOLUTE", step=10,
        description="Seconds to simulate; 0 runs until the shape has formed and held (for moving targets: "
                    "until 3 s after their last keyframe)")
    start_frame: IntProperty(name="Start Frame", default=1, min=0, max=1_000_000,
                             description="The frame the forming starts on (the targets' rest pose is taken here)")


class FluidFormPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    cli_path: StringProperty(
        name="fluidform executable", subtype="FILE_PATH", default="",
        description="The fluidform CLI (empty: $FLUIDFORM_BIN, then fluidform on PATH)")
    output_dir: StringProperty(
        name="Output folder", subtype="DIR_PATH", default="",
        description="Where runs are written (empty: fluidform/ next to the saved .blend, else the temp folder); "
                    "the point cache stays there for the Mesh Cache modifier")
    keep_particle_frames: BoolProperty(
        name="Keep particle frames", default=False,
        description="Keep the run's particles/*.ply (every frame is also in particles.pc2)")

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "cli_path")
        col.prop(self, "output_dir")
        col.prop(self, "keep_particle_frames")


classes = (FluidFormSettings, FluidFormPreferences)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.fluidform = bpy.props.PointerProperty(type=FluidFormSettings)
    bpy.types.WindowManager.fluidform_progress = FloatProperty(
        name="Fluid Form", subtype="PERCENTAGE", min=0.0, max=100.0, precision=0,
        description="Progress of the running Form")


def unregister():
    del bpy.types.WindowManager.fluidform_progress
    del bpy.types.Scene.fluidform
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
