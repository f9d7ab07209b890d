"""Column layout of the flat arrays passed to the kernels: the only place slots are defined.

Nodes and segments live in global arrays; a line owns a contiguous block of segment slots and a
contiguous block of interior-node slots (capacity for payout)::

    bottom end (anchor back tip / release point / seabed anchor)
        node L0 ──seg s0── node L1 ──seg s1── ... ──seg s(n-1)── node Ln = top (vessel)

Local node 0 is the line's bottom node, local node n its top node; local nodes 1..n-1 are the global
nodes ``NODE_START + k - 1``. Segment ``SEG_START + k`` joins local node k to k+1. Payout changes only the
top segment and adds or removes the node below it.
"""

# node kinds
NODE_INACTIVE = -1
NODE_FREE = 0
NODE_VESSEL = 1  # prescribed by a vessel track; REF = vessel index
NODE_BODY = 2  # rigidly attached to the anchor at axial coordinate BODY_S
NODE_WELDED = 3  # moves with node REF (its mass and loads go to REF)
NODE_FIXED = 4  # held in space

# node_i columns
NI_KIND = 0
NI_REF = 1
NI_LINE = 2
N_NODE_I = 3

# node_f columns
NF_POINT_MASS = 0  # lumped mass [kg]
NF_POINT_VOLUME = 1  # displaced volume [m^3]
NF_POINT_CDA = 2  # Cd * area, isotropic [m^2]
NF_POINT_CA = 3  # added-mass coefficient on POINT_VOLUME
NF_BODY_S = 4  # axial coordinate on the anchor from its COG, + towards the tip [m]
N_NODE_F = 5

# seg_i columns
SI_A = 0
SI_B = 1
SI_MAT = 2
SI_LINE = 3
SI_ACTIVE = 4
N_SEG_I = 5

# seg_f columns
SF_L0 = 0  # unstretched length [m]
N_SEG_F = 1

# mat_f columns
MF_EA = 0  # [N]
MF_MASS = 1  # mass per metre in air [kg/m]
MF_SUBMERGED = 2  # submerged mass per metre [kg/m]
MF_D = 3  # hydrodynamic diameter [m]
MF_CDN = 4
MF_CDT = 5
MF_CAN = 6
MF_CAT = 7
MF_ZETA = 8  # axial damping ratio of one segment's axial mode
MF_MBL = 9  # [N]
MF_SEABED_D = 10  # width the seabed bears per metre of line [m]: the diameter (0: the line passes through it)
N_MAT_F = 11

# line_i columns
LI_SEG_START = 0
LI_SEG_CAP = 1
LI_NSEG = 2
LI_NODE_START = 3
LI_NODE_CAP = 4
LI_BOTTOM = 5
LI_TOP = 6
LI_PAYOUT = 7  # 1 if the top segment may change length
LI_CLAMPED = 8  # set by the kernel when haul-in hit the minimum length
N_LINE_I = 9

# line_f columns
LF_L_NOM = 0  # nominal length of a new top segment [m]
LF_L_MIN_TOP = 1  # merge the top segment below this length [m]
LF_L_MAX_TOP = 2  # split the top segment above this length [m]
LF_RATE = 3  # payout rate [m/s], + pays out
LF_MAX_TENSION = 4  # running maximum of segment tension [N]
N_LINE_F = 5

# env_f slots
EF_DEPTH = 0
EF_G = 1
EF_RHO = 2
EF_KBOT = 3
EF_CBOT = 4
EF_MU = 5
EF_FRIC_V = 6
EF_CUR_DX = 7
EF_CUR_DY = 8
EF_CUR_SCALE = 9
EF_TRACK_T0 = 10
EF_TRACK_DT = 11
EF_SPEED_LIMIT = 12
EF_STRAIN_LIMIT = 13
EF_SLACK_SMOOTHING = 14  # statics only: strain scale of the smoothed tension-only law (0 = exact)
EF_SEABED_SMOOTHING = 15  # statics only: penetration scale of the smoothed seabed contact [m] (0 = exact)
N_ENV_F = 16

# body_f slots (anchor rigid body)
BF_ACTIVE = 0
BF_MASS_AXIAL = 1  # mass for axial acceleration (structure + flooded water + attached points) [kg]
BF_M11 = 2  # normal-plane generalized mass: translation [kg]
BF_M12 = 3  # translation-rotation coupling [kg m]
BF_M22 = 4  # rotation about a transverse axis through the COG [kg m^2]
BF_WEIGHT = 5  # gravity on structure + flooded water [N]
BF_BUOYANCY = 6  # rho g V_outer [N]
BF_S_BUOY = 7  # axial coordinate of the centre of buoyancy [m]
BF_S_TIP = 8
BF_S_BACK = 9
BF_TIP_CDA = 10  # tip pressure drag Cd*A [m^2]
BF_BACK_CDA = 11
BF_LENGTH = 12
N_BODY_F = 13

# contact_f slots (contact between line nodes and the anchor's surface, physics/contact.py)
CF_ON = 0  # 1 where contact is modelled, 0 where lines pass through the anchor unhindered
CF_STIFFNESS = 1  # normal stiffness of one node's contact [N/m]
CF_RESTITUTION = 2  # coefficient of restitution of a node landing on the anchor [-]
CF_ZETA = 3  # damping ratio of a node's contact oscillation, set by the restitution [-]
CF_SPEED = 4  # characteristic contact speed the stiffness was chosen for [m/s]
CF_MU = 5  # Coulomb friction coefficient [-]
CF_STICK_SPEED = 6  # sliding speed below which friction is viscous (regularised stick) [m/s]
CF_SEGMENTS = 7  # 1 where the contact also acts on segments cutting deeper than their nodes (segment_contact.py)
CF_TURNING = 8  # 1 while the static solver's system takes the turning of the segment contacts' normals
# (statics_contact.py, switched on by statics_stages.Stage for a stage that creeps); 0 as compiled
N_CONTACT_F = 9

# contact_out slots (what the contact did, physics/contact.py: add_contact_loads)
CO_FORCE = 0  # magnitude of the net contact force on the anchor at the last load evaluation [N]
CO_PEAK_FORCE = 1  # its running maximum (reset at the release) [N]
CO_NODES = 2  # nodes inside the anchor's surface at the last load evaluation
CO_DEPTH = 3  # deepest of them [m]
CO_PEAK_DEPTH = 4  # its running maximum (reset at the release) [m]
CO_SEGMENTS = 5  # segments cutting into it deeper than their nodes (physics/segment_contact.py), last evaluation
N_CONTACT_OUT = 6

# contact_cache columns: a contact candidate's start-of-step state in the implicit step (implicit_contact.py)
CC_READY = 0  # 1 once computed in this step
CC_DEPTH = 1  # depth [m] (negative: gap)
CC_NORMAL = 2  # outward normal (3)
CC_VEL = 5  # velocity relative to the anchor's point there (3) [m/s]
CC_FORCE = 8  # the contact force at the start of the step (3) [N]
N_CONTACT_CACHE = 11

# near_skin slots: the contact's list of what lies near the anchor (physics/contact_broadphase.py)
NEAR_ON = 0  # 1 while the step's load evaluation uses the lists
NEAR_MOVED_M = 1  # how far the nodes and the COG can have closed on each other since the lists were built [m]
NEAR_SPEED_M_S = 2  # a bound on the free nodes' speed relative to the COG after the last step (inf: not known) [m/s]
NEAR_LONGEST_M = 3  # the longest active segment when the lists were built [m]
NEAR_BUILDS = 4  # how many times the lists were built in this workspace (a count for the benchmarks)
N_NEAR = 5

# contact_shape columns: the anchor's surface as coaxial cylinders (physics/contact.py)
CS_FRONT = 0  # axial coordinate of the end towards the tip, from the COG [m]
CS_BACK = 1  # axial coordinate of the end towards the back [m]
CS_RADIUS = 2  # [m]
CS_FRONT_INNER = 3  # inner radius of the front end's face: 0 a full disc, the neighbour's radius an annular step [m]
CS_BACK_INNER = 4  # (equal to CS_RADIUS where a neighbour at least as wide covers the end: no face)
N_CONTACT_SHAPE = 5

# body_q columns (quadrature points along the anchor)
BQ_S = 0
BQ_DS = 1
BQ_CDN_D = 2  # cd_normal * outer diameter [m]
BQ_CDT_PID = 3  # cd_tangential * pi * outer diameter [m]
N_BODY_Q = 4

# body state (12): position of COG, velocity, axis unit vector (back -> tip), angular velocity
BS_POS = 0
BS_VEL = 3
BS_AXIS = 6
BS_OMEGA = 9
N_BODY_STATE = 12

# kernel status codes
STATUS_RUNNING = 0
STATUS_TOUCHDOWN = 1
STATUS_TIME_LIMIT = 2
STATUS_NONFINITE = 3
STATUS_SPEED_LIMIT = 4
STATUS_STRAIN_LIMIT = 5
STATUS_BREAKING_LOAD = 6  # only where the caller asks for it (a coarse step that may be repeated finer)
STATUS_NAMES = {
    STATUS_RUNNING: "running",
    STATUS_TOUCHDOWN: "touchdown",
    STATUS_TIME_LIMIT: "time limit",
    STATUS_NONFINITE: "non-finite",
    STATUS_SPEED_LIMIT: "speed above limit",
    STATUS_STRAIN_LIMIT: "strain above limit",
    STATUS_BREAKING_LOAD: "tension above breaking load",
}

# touchdown record slots (filled by the kernel at the interpolated touchdown instant)
TD_TIME = 0
TD_TIP = 1  # 3
TD_VEL = 4  # 3: velocity of the tip
TD_AXIS = 7  # 3
N_TD = 10

# history record columns
H_TIME = 0
H_TIP = 1  # 3
H_TIP_VEL = 4  # 3
H_AXIS = 7  # 3
H_OMEGA = 10  # 3
N_HIST = 13
