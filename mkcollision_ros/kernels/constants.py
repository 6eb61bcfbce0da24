"""The kernels' codes and layouts (shape, status and method codes, the result row, the
outcome of a pair kernel run before GJK), and every iteration cap and tolerance of the
kernels, with its unit: no kernel compares against a bare numeric tolerance or loops to
a bare count of its own.

Tolerances are relative to a length scale of the pair, ``scale`` (metres): the sum of
the two shapes' bounding radii.  Multiplying by the scale keeps a millimetre object and
a kilometre object equally well resolved.
"""

# --- shape codes, in the canonical pair order (a pair kernel has code_a <= code_b) ----
SPHERE = 0
ELLIPSOID = 1
BOX = 2
CAPSULE = 3
CYLINDER = 4
CONE = 5
CONVEX = 6
PLANE = 7
N_SHAPE_TYPES = 8
SHAPE_NAMES = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex", "plane")

# --- layout of one row of the shape parameter table (float64[N_PARAMS]) ----------------
N_PARAMS = 8
P_GROUPS = 0     # convex: groups of its points, two rows each right after them in verts
                 # (0: none; mkcollision_ros.hull.support_groups, geometry._grouped_support)
P_FAN_FACES = 1  # convex: its hull's faces, edges and vertices stored after its points
P_FAN_EDGES = 2  # in verts for pairs/ellipsoid_convex.py (0 faces: none, and then maybe group rows;
P_FAN_VERTS = 3  # mkcollision_ros.hull.fan_rows has the layout)
FAN_MAX_POINTS = 64  # hulls of at most this many kept points get their fan (fan_rows): the
                     # exact kernel walks every face, edge and vertex, which pays against
                     # GJK/EPA only on small hulls, and fan_rows' builder is O(points^4)
P_ROLL = 3       # ellipsoid: radius of a ball that rolls freely inside it (m), see
                 # geometry.py (0 is always valid: the core is then the ellipsoid)
P_MARGIN = 6     # padding radius added around the shape (m)
P_RADIUS = 7     # bounding radius about the body origin, margin included (m)

# --- result status codes (see mkcollision_ros.results.Status) --------------------------
ST_SEPARATED = 0
ST_TOUCHING = 1
ST_PENETRATING = 2
ST_FAILED = 3
ST_NOT_RUN = 4

# --- method codes -----------------------------------------------------------------------
M_AUTO = 0
M_GJK_EPA = 1
M_MPR = 2
M_ANALYTIC = 3
M_ELLIPSOID_EXACT = 4
M_ELLIPSOID_SAMPLED = 5
METHOD_NAMES = ("auto", "gjk_epa", "mpr", "analytic", "ellipsoid_exact", "ellipsoid_sampled")

# --- the touching rule -------------------------------------------------------------------
# A pair is in contact iff signed distance <= TOUCH_TOL * scale.  |distance| within the
# tolerance is reported as TOUCHING, below it PENETRATING, above it SEPARATED.
TOUCH_TOL = 1e-9

# --- what a pair kernel run before GJK decided (pairs/; gjk_epa.gjk_epa_ws) -----------
# Each such kernel fills res (10,) = [h, normal (3), point on A (3), point on B (3)] in
# A's frame, on the cores (the shapes shrunk by their inflation radii), and returns one of:
PRE_UNDECIDED = -1         # nothing proved: GJK and EPA answer the pair
PRE_UNPROVED = 0           # (the fan kernels) no proof that the cores overlap: GJK runs, and
                           # once it finds them overlapping the kernel runs again in EPA's place
PRE_EXACT = 1              # res holds the cores' certified depth h > 0 or their exact distance
                           # -h >= 0, with the normal from A to B and the witness points
PRE_APART = 2              # a plane proves the cores farther apart than the caller's ``stop``
                           # (m): -h is that bound, res's points lie on the two cores

# --- batch kernel ------------------------------------------------------------------------
NP_CHUNK = 128             # fewest pairs per block of collide_batch (jit.n_blocks)

# --- GJK ---------------------------------------------------------------------------------
GJK_MAX_ITERS = 128        # iterations (support evaluations)
GJK_REL_TOL = 1e-12        # relative duality gap on the squared distance (dimensionless)
GJK_POLISH_TOL = 1e-3     # with an ellipsoid: try Newton's method once the gap < tol |v|^2
                           # (dimensionless)
GJK_FLAT_TOL = 1e-9        # tetrahedra with 6|volume| <= tol * (longest edge)^3 are flat
GJK_FACE_TOL = 0.1         # on cores apart, GJK tries the face tests (polish_faces) once its
                           # gap is below this * |v|^2 (dimensionless)
PLANE_NORMAL_COS = 0.99    # GJK's normal is the final triangle's plane normal where that lies
                           # within this cosine of the closest point's direction
GJK_CAP_GAP = 1e-6         # GJK out of iterations: its distance stands if the last duality
                           # gap is below this * scale, else ST_FAILED (dimensionless)
SLIVER_TOL = 1e-10         # a tetrahedron whose vertex lies less than this (relative to the
                           # opposite face's size and its edge) off that face's plane never
                           # holds the origin (simplex.py; dimensionless)
BARY_SLACK = 1e-9          # barycentric coordinates this far outside [0, 1] still count as
                           # inside the triangle (simplex.py, epa.py's witnesses;
                           # dimensionless)

# --- EPA ---------------------------------------------------------------------------------
EPA_MAX_ITERS = 255        # added vertices
EPA_MAX_FACES = 512        # face slots in the fixed polytope buffer
EPA_REL_TOL = 1e-8         # stop when support gain < tol * scale (dimensionless)
EPA_PATTERN_STEP = 1e-2    # the caps' pattern search over directions (epa._polish_min_support):
EPA_PATTERN_STEP_MIN = 1e-10  # its first step and the step that ends it (rad); at most
                           # 4 * EPA_MAX_ITERS supports
EPA_POLISH_TOL = 1e-3      # try Newton's method (polish_newton._epa_polish) once the support gain
                           # < tol * scale, and once more at EPA_POLISH_RETRY * tol * scale if
                           # it gave up
EPA_POLISH_RETRY = 0.01    # (dimensionless)
EPA_SLIVER_BARY = 0.1      # a witness whose barycentric coordinates on EPA's face fall more
                           # than this outside [0, 1] comes from a sliver face: the clamped
                           # closest point is taken instead (dimensionless)
POLISH_STEP_DONE = 1e-6    # Newton's method and the crease search end once the step they
                           # would take next is below this (rad), at the point they are
                           # at: the direction is then within ~1e-6 rad of the minimum and
                           # h within ~1e-12 * scale of it.  That last step is not taken:
                           # it would cost a support for nothing the tolerances see
EPA_POLISH_ITERS = 6       # its steps (support evaluations)
EPA_POLISH_STEP = 0.05     # longest step it may take (rad)
EPA_POLISH_CAP = 0.5       # its minimum is kept only if no direction farther than this
                           # from its normal can be deeper by EPA's faces (rad;
                           # certificates._polish_is_global)
EPA_FACE_TOL = 1e-1         # test a box's face normal or a cylinder's axis within
                           # EPA_KINK_NEAR rad of EPA's best face normal for the minimum
                           # (polish_faces._face_polish) once the support gain < tol * scale
EPA_FACE_EVALS = 3         # at most this many supports for those tests per pair, in EPA
                           # and again in GJK on cores apart (gjk._gjk)
EPA_FACE_CAP_MAX = 1.5     # largest EPA_POLISH_CAP for a minimum found so (rad); the cap
                           # itself is proved by the test (certificates._face_basin)
EPA_KINK_NEAR = 0.05       # try the polish along a cylinder's side (polish_crease._kink_polish)
                           # when the best face's normal n has |n . axis| below this (a
                           # box: for one of its axes only; near two, n is near a face
                           # normal; dimensionless)
EPA_KINK_ITERS = 8         # its support evaluations
EPA_KINK_STEP = 0.1        # longest step it may take along the side's circle (rad)
EPA_KINK_CAP_CAPSULE = 0.05  # EPA_POLISH_CAP for a minimum on a capsule's crease (rad):
                           # deeper minima off it lie 0.09-0.19 rad away
EPA_KINK_CAP_BOX = 0.1     # and on a box edge's crease against an ellipsoid (rad): the
                           # deeper minimum of a vertex's region can lie 0.2 rad away
                           # (tests/regression_scenes.json,
                           # mkc_crease_polish_wrong_basin_ellipsoid_box)
EPA_VERTEX_CAP_MIN = 0.05  # least basin cap for a box vertex's minimum against an ellipsoid
                           # (certificates._vertex_cap): its angle to the box's nearest crease
NEWTON_DET_MIN = 1e-6      # Newton's step (polish_newton) needs its 2x2 Hessian's determinant
                           # above this * trace^2 (dimensionless)
CREASE_SLOPE_TOL = 1e-6    # the crease search's minimum counts once h's slope along the
                           # crease is below this * scale per rad (polish_crease)
FACE_MIN_EDGE = 1e-9       # polish_faces: a hull edge shorter than this * scale has no crease
FACE_MIN_RADIUS = 1e-7     # ... and a face test needs its foot this * scale inside the face
                           # (the disc of its basin, a half edge, a triangle's rim)

# --- MPR ---------------------------------------------------------------------------------
MPR_MAX_ITERS = 128        # portal refinements
MPR_REL_TOL = 1e-10        # portal-to-boundary gap, relative to scale
MPR_NUDGE = 1e-9           # coincident centres: the first portal point moved this * scale off
                           # the origin (along x)
MPR_PARALLEL_SIN = 1e-14   # the first two portal points are collinear with the origin when the
                           # sine of their angle is below this (dimensionless)

# --- exact ellipsoid distance ------------------------------------------------------------
ELL_MAX_ITERS = 200        # bisection steps on the Lagrange multiplier (float64 exhausts ~1100)

# --- layout of one pair result row (float64[OUT_SIZE]), every vector in A's frame or,
# after the batch kernel transforms it, in the world frame -------------------------------
OUT_DIST = 0       # signed distance (m): > 0 apart, < 0 penetrating (depth = -distance)
OUT_NORMAL = 1     # 1:4 unit normal from A to B; moving B by depth along it separates
OUT_PA = 4         # 4:7 witness point on A's surface
OUT_PB = 7         # 7:10 witness point on B's surface
OUT_ITERS = 10     # iterations used by the method
OUT_METHOD = 11    # method code (M_*)
OUT_SIZE = 12

# --- GJK / EPA extras (gjk_epa.py) -------------------------------------------------------
GJK_ABS_TOL = 1e-12        # stop GJK when the distance bound gap < tol * scale (dimensionless)
EPA_DEGEN_TOL = 1e-12      # flat Minkowski difference: volume/extent below tol * scale
EPA_WITNESS_SHIFT = 1e-7   # witness fix-up: B pulled apart by depth + shift * scale (m/m)
EPA_FAIL_GAP = 1e-4        # EPA caps hit: FAILED when upper - lower depth bound > tol * scale

# --- single tests the kernels share, by role -------------------------------------------
SUPPORT_TIE = 1e-12        # two support values, or a point and a plane, within this * scale
                           # are equal (a minimum no deeper than a candidate, a point on a
                           # face or within a segment, coincident centres; geometry: times a
                           # shape's radius; dimensionless)
NO_DIRECTION = 1e-12       # a vector built from unit vectors (a cross product, a unit vector's
                           # components off an axis) shorter than this has no direction
                           # (dimensionless)
PARALLEL_SIN = 1e-9        # a unit direction and an axis whose cross product is shorter than
                           # this are parallel (box_capsule, cylinder_convex; dimensionless)
AXES_SIN_MIN = 1e-6        # two axes whose angle has a sine below this do not cross (the
                           # crossing tests of cylinder_cylinder and polish_faces;
                           # dimensionless)
ROLL_SHRINK = 1e-12        # an ellipsoid's rolling ball is shrunk by this (relative) so that
                           # rounding cannot put it outside the ellipsoid (dimensionless)
DIV_FLOOR = 1e-300         # a length at or below this is zero to a division (m)
JACOBI_SWEEPS = 50         # sweeps of the Jacobi eigen-solver (ellipsoid.py) at most
JACOBI_OFF_TOL = 1e-36     # the Jacobi eigen-solver (ellipsoid.py) stops once the squared
                           # off-diagonal part is below this * the squared diagonal

# --- broad phase (broadphase.py) --------------------------------------------------------
PLANE_AXIS_TOL = 1e-12     # planes whose world normal has off-axis components below this
                           # are axis-aligned (dimensionless, components of a unit vector)

# --- closed forms (pairs/) --------------------------------------------------------------
SE_HALVINGS = 1100         # sphere-ellipsoid: halvings of the multiplier's bracket toward 0 at
                           # most (float64 underflows after ~1100)
SE_ROOT_STOP = 4e-16       # sphere-ellipsoid: Newton's method on the multiplier u ends at a
                           # step below this * u (rounding)
SAT_EDGE_BIAS = 1e-9       # box-box: an edge-edge axis is taken only if its overlap is below
                           # the best face axis's by this * scale
SEGMENT_SIN2 = 1e-14       # capsule-capsule: segments whose angle's squared sine is below this
                           # are parallel (dimensionless)
SEGMENT_MEET = 1e-15       # ... and whose closest points are within this * scale meet

# --- pair kernels run before GJK (pairs/), in the canonical pair order ------------------
# ellipsoid-box (pairs/ellipsoid_box.py)
BE_POINT_ITERS = 40        # Newton steps on the Lagrange multiplier of a box vertex's
                           # nearest point on the ellipsoid (from t = 0, kept in the root's
                           # bracket; iterations)
BE_ROOT_STOP = 1e-15       # the Newton steps on a box vertex's multiplier end at a step this
                           # small relative to the multiplier or the least squared radius
BE_EXACT = 1e-12           # a distance is exact when its closest points are this much
                           # (times scale, dimensionless) farther apart than the separating
                           # plane's gap, at most
# ellipsoid-convex and cylinder-convex over a hull's normal fan (pairs/normal_fan.py,
# pairs/ellipsoid_convex.py, pairs/cylinder_convex.py)
HE_ITERS = 60              # cap of every 1-D root search (iterations)
HE_POLE_SEP = 1e-9         # poles (the ellipse's or E's squared radii, relative to the
                           # largest) closer than this: degenerate, left to GJK/EPA
HE_WEIGHT_FLOOR = 1e-24    # a point's weight l_i P_i^2 at or below this * l_max * scale^2
                           # lies on an axis: degenerate, left to GJK/EPA
HE_ROOT_SLACK = 1e-9       # the secular function's root brackets keep off the poles by this *
                           # gap, and its no-root test allows this much rounding (relative)
HE_PROGRESS_RTOL = 1e-12   # the unit-ball GJK stops when |v|^2 gains less than this (relative)
HE_BALL_ITERS = 32         # cap of the GJK steps in E's unit-ball frame
                           # (ellipsoid_convex._unit_ball_test; cylinder_convex._cyl_gjk's
                           # too; iterations)
HE_BALL_TOL = 1e-9         # a point of B that far inside the unit ball proves overlap
                           # (relative to the unit ball, dimensionless)
HE_ROOT_RTOL = 1e-13       # a root's last Newton step (relative, dimensionless; the depth
                           # needs ~1e-10)
HE_DMIN_RTOL = 1e-12       # the search for phi's minimum between two poles gives up here
                           # (relative, dimensionless)
HE_SUPPORT_TOL = 1e-12     # a foot counts if B's support along -n is within this * scale
                           # (dimensionless)
HE_FOOT_SLACK = 1e-9       # normal_fan._plane_feet takes the right root for a point this
                           # far outside the ellipse too (relative, dimensionless): at
                           # touching the point lies on it, and rounding may put it just
                           # outside
HE_FAN_SLACK = 4e-10       # the edges' chord bound takes an edge's point on its faces'
                           # planes, within hull._FAN_TOL (1e-10) of the points' extent
                           # (<= 2 sqrt(3) radius_B), so it is lowered by this * scale
                           # (dimensionless)
# box-cylinder (pairs/box_cylinder.py)
BC_MAX_LEVEL = 4           # halvings of an arc whose bound is too low (then EPA; iterations)
BC_ROOT_ITERS = 60         # Newton steps on an edge circle's multiplier at most
BC_ROOT_STOP = 1e-16       # a Newton step on an edge circle's multiplier this small relative
                           # to 1 + |t| ends the search (rounding)
BC_FEAT = 1e-9             # a box axis this close to normal to m: m is on its edge circle
                           # (|cosine|, dimensionless)
# the cylinder pairs (pairs/cylinder_common.py, cylinder_cylinder.py, cylinder_convex.py)
CC_NEWTON_ITERS = 8        # Newton steps on a rim's angle (~4 taken on average; iterations)
CC_HALF_TAN_MAX = 0.25     # longest step: tan of half its angle (dimensionless, ~0.49 rad);
                           # far from the minimum F'' may mislead
CC_HALF_TAN_DONE = 5e-5    # a step this short ends the search (tan of half its angle,
                           # dimensionless, 1e-4 rad; the angle's error is then of its
                           # square, and the ball's of its square)
CC_RIMS = 2                # rims solved at most, deepest bound first (a third or fourth
                           # certifies no more pairs)
CC_COVER_STEPS = 12        # greedy steps of cylinder_common._cover at most (each raises the
                           # level covered; iterations)
CC_CROSS_RINGS = 16        # rings of cylinder_cylinder._crossing_global at most
HC_GJK_ITERS = 16          # steps of the 2-D GJK on a hull's shadow
                           # (cylinder_convex.collide_cylinder_convex_ball, ~4 taken;
                           # iterations)

# --- contact manifold (manifold.py) and persistence (persistence.py) --------------------
REF_TIE = 1e-3             # A's face is the reference face unless B's is better aligned with
                           # the normal by more than this (cosine, dimensionless)
CONTACT_SAME_SQ = 1e-24    # two clipped points this close (squared distance over both
                           # witnesses, m^2) are one
FACE_SIN = 0.05            # sin of the angle (~2.9 deg) within which a cap / side is a face
                           # (dimensionless)
FACE_SLACK = 0.05          # convex hull face tolerance, relative to the hull's diameter
                           # (dimensionless)
REF_COS = 0.9              # the reference face normal must be within ~26 deg of n (cosine,
                           # dimensionless)
# the reduction to max_contacts (persistence._reduce) treats as equal, and gives to the
# older contact: depths within DEPTH_TIE x merge_distance (dimensionless), squared
# distances and areas within REDUCE_TIE of the largest (relative, dimensionless)
DEPTH_TIE = 1e-3
REDUCE_TIE = 1e-3
