"""The command line's vocabulary: every option name with the one meaning it has in every command that takes
it, and the metavar ``--help`` shows for it.

A new option takes a name from here with its meaning, or adds a new name; a name is never given a second
meaning (tests/test_vocabulary.py walks every command against this table).  A name retired for a clearer
one goes into :data:`RENAMED`: it still works, with one ``warning:`` line naming the new one
(cli/_renamed.py rewrites it before the command line is parsed); the names changed before the first
release are not accepted (docs/changelog.md).
"""

from __future__ import annotations

#: long option name → (metavar, meaning); a flag's metavar is empty
VOCABULARY: dict[str, tuple[str, str]] = {
    # -- every working command: outputs, printing, resources
    "--out": ("PATH", "the output written: a folder, a data set or a model file"),
    "--overwrite": ("", "replace an earlier output of translucency (never anything else)"),
    "--quiet": ("", "no progress and no information lines"),
    "--json": ("", "one JSON object on stdout"),
    "--json-out": ("PATH", "the JSON summary also written to this file"),
    "--max-memory": ("SIZE", "most memory the command may use, checked against its estimate"),
    "--scheduler": ("WHERE", "where work runs: threads, local:N, tcp://HOST:PORT"),
    "--version": ("", "the version"),
    "--help": ("", "the help"),
    # -- samples and objects
    "--material": ("TEXT", "a sample generator (or a material of `translucency materials`)"),
    "--volume": ("PATH", "a user's volume (.npz)"),
    "--mesh": ("PATH", "a mesh file"),
    "--scale": ("FLOAT", "millimetres per mesh unit"),
    "--up": ("TEXT", "the mesh file's up axis"),
    "--size": ("W H T", "a generated slab's width, height and thickness, mm"),
    "--voxel": ("FLOAT", "voxel size of a generated sample or filling, mm"),
    "--g": ("FLOAT", "Henyey-Greenstein anisotropy of a generated sample"),
    "--eta": ("FLOAT", "relative index of refraction of the sample's boundary (default: the sample's own)"),
    "--index-matched": ("", "no Fresnel reflection at the boundary: --eta 1"),
    "--seed": ("INT", "random seed"),
    "--sample-seed": ("INT", "seed of the generated sample"),
    # -- acquisition
    "--photons": ("INT", "photons per incident point and channel"),
    "--points": ("INT", "how many incident points (laser positions)"),
    "--grid": ("INT", "incident points per axis"),
    "--span": ("FLOAT", "side of the incident grid, mm"),
    "--pitch": ("FLOAT", "pixel size on the sample, mm"),
    "--window": ("FLOAT", "window side around each incident point, mm"),
    "--tilt": ("DEGREES", "the scan's one beam tilted from the normal, degrees"),
    "--incidence": ("DEGREES", "oblique beams besides the normal one: their angle from the normal"),
    "--azimuths": ("INT", "azimuths per --incidence angle"),
    "--exit-bins": ("INT", "exit direction bins"),
    "--chunk": ("INT", "incident points per chunk of work"),
    "--dtype": ("TEXT", "the floating-point type the output stores its arrays in: float32 or float16"),
    "--reentry": ("", "light leaving one part through the air walks on in another"),
    "--unscattered": ("TEXT", "how light that leaves without scattering is kept"),
    # -- cameras and photographs
    "--camera": ("X Y Z", "a camera's position relative to the sample's centre, mm"),
    "--cameras": ("INT", "how many cameras"),
    "--fov": ("FLOAT", "horizontal field of view, degrees"),
    "--resolution": ("W H", "image width and height, pixels"),
    "--spp": ("INT", "samples per pixel of the path-traced photographs"),
    "--format": ("TEXT", "image file format"),
    "--beam": ("FLOAT", "radius of the laser's spot on the surface, mm"),
    "--beam-rms": ("FLOAT", "the laser beam's rms radius, mm"),
    "--checkerboards": ("", "intrinsics given as checkerboard photographs"),
    "--exposures": ("TEXT", "exposures per camera and shot"),
    # -- import
    "--positions": ("PATH", "the table of laser positions"),
    "--calibration": ("PATH", "the camera calibration"),
    "--gain": ("FLOAT", "pixel value per unit exitance per second"),
    "--extra-camera": ("FOLDER,POSITIONS,CALIBRATION", "another camera's photographs"),
    "--supersample": ("INT", "sub-samples per output pixel side"),
    "--specular-radius": ("FLOAT", "pixels this close to the laser masked, mm"),
    "--dilate": ("INT", "growth of the saturated mask, image pixels"),
    "--floor": ("FLOAT", "pixel values below this masked"),
    "--sample-size": ("W,H", "the sample's width and height, mm"),
    "--exit-law": ("TEXT", "radiance to exitance"),
    # -- fit
    "--model": ("TEXT", "the model family fitted"),
    "--terms": ("N", "exponential terms n per profile"),
    "--directions": ("M", "directions m of the anisotropic model"),
    "--weighting": ("TEXT", "how residuals are weighted"),
    "--colour": ("TEXT", "how the colour channels share a fall-off"),
    "--exclusion": ("FLOAT", "pixels closer than this to x_i ignored, mm"),
    "--rounds": ("INT", "most alternation rounds"),
    "--alpha-radius": ("FLOAT", "alpha's statistics pooled within this distance, mm"),
    # -- evaluate
    "--report": ("PATH", "the report's folder"),
    "--compare": ("PATH", "another model file of the same data"),
    "--profiles": ("I,J,K", "incident points whose profiles are drawn"),
    "--truth": ("PATH", "an independent acquisition of the same incident points"),
    "--paper": ("", "the paper's model: each point's radial profile alone"),
    "--transport": ("KIND", "the transport drawn, by its registered name (default, walked, paper)"),
    # -- render, export, view
    "--light": ("LIGHT", "a light in the object's frame"),
    "--view": ("X,Y,Z", "direction from the object's centre towards the camera"),
    "--exposure": ("HOW", "exposure of the PNGs"),
    "--reference": ("", "also path-trace the reference and compare"),
    "--reference-render": ("PATH", "a render folder with its path-traced reference"),
    "--radius": ("FLOAT", "near radius of the transport, mm"),
    "--angles": ("", "the model's lean drawn"),
    "--scene": ("PATH", "a Mitsuba 3 scene file"),
    "--object": ("ID=FILE", "a shape of the scene that is this per-vertex model"),
    "--scene-unit": ("FLOAT", "millimetres per scene unit"),
    "--irradiance-samples": ("INT", "irradiance samples per vertex"),
    "--passes": ("INT", "light-in / through-the-body passes"),
    "--max-depth": ("INT", "longest light path, bounces"),
    "--roughness": ("FLOAT", "GGX roughness of the boundary"),
    "--picture-spp": ("INT", "samples per pixel of our picture"),
    "--reference-spp": ("INT", "samples per pixel of the path-traced reference"),
    "--ply": ("PATH", "the mesh written as PLY"),
    "--gltf": ("PATH", "glTF 2.0 binary written"),
    "--mitsuba": ("DIR", "a Mitsuba 3 scene of the estimated medium written into this folder"),
    "--preview": ("", "a quick rehearsal: smaller settings where none are given"),
    "--export": ("PATH", "a static page written into this folder"),
    "--port": ("INT", "the port served on"),
    "--browser": ("", "open the page in the default browser"),
    "--sky": ("ENV", "the environment light"),
    "--bands": ("INT", "bands of the spherical-harmonics light basis"),
    "--seconds": ("FLOAT", "serve this long, then stop"),
}

#: command → {retired name: the words that replace it}; the old name still works, with one warning line
RENAMED: dict[str, dict[str, list[str]]] = {
    "acquire planar": {"--angle": ["--tilt"]},
    "fit": {"--float16": ["--dtype", "float16"]},
    "render": {"--spp": ["--reference-spp"]},
    "render scene": {"--spp": ["--reference-spp"], "--samples": ["--irradiance-samples"]},
}

#: short option → the long option it is in every command
SHORT: dict[str, str] = {
    "-o": "--out",
    "-q": "--quiet",
    "-m": "--material",
    "-n": "--terms",
    "-N": "--photons",
    "-p": "--positions",
    "-c": "--calibration",
}

#: long option name → the metavar --help shows
METAVARS: dict[str, str] = {name: metavar for name, (metavar, _) in VOCABULARY.items()}
