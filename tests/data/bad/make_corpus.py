#!/usr/bin/env python3
"""Writes the bad-input corpus (tests/data/bad/*/) and its MANIFEST.tsv from the valid files in
tests/data/bad/base/ (made by rotacal itself; see README.md beside this script). Each entry is a
file, the command that is given it, the exit code it must end with (1 bad input, 2 usage), a
fragment the one-line message must contain, and what the message must name: `line` (the input
file and a line >= 1), `in` (the input file), `out` (the output path), `db`, or `-`.
Run from the repository root: python3 tests/data/bad/make_corpus.py (the files are committed)."""
import json, os, shutil, sqlite3, copy

HERE = os.path.dirname(os.path.abspath(__file__))
BASE = os.path.join(HERE, 'base')
entries = []

def rd(name, mode='r'):
    with open(os.path.join(BASE, name), mode) as f:
        return f.read()

def add(kind, name, content, template, code, fragment, locus):
    d = os.path.join(HERE, kind)
    os.makedirs(d, exist_ok=True)
    p = os.path.join(d, name)
    data = content if isinstance(content, bytes) else content.encode()
    with open(p, 'wb') as f:
        f.write(data)
    entries.append((f'{kind}/{name}', template, str(code), fragment, locus))

RAW = '"__RAW__%s__"'
def raw(x):
    return '__RAW__%s__' % x

def dump(doc):
    t = json.dumps(doc, indent=1)
    import re
    return re.sub(r'"__RAW__(.*?)__"', lambda m: m.group(1), t) + '\n'

def setp(doc, path, value):
    doc = copy.deepcopy(doc)
    cur = doc
    for k in path[:-1]:
        cur = cur[k]
    if value is DEL:
        del cur[path[-1]]
    else:
        cur[path[-1]] = value
    return doc

DEL = object()

# ---------------------------------------------------------------- machines
M = json.loads(rd('machine.json'))
T_MACHINE = 'plan --cycle touch154 --machine {in} -o {out}.json'
machine_cases = [
    ('ball_nan', ['probe', 'ball_diameter_mm'], raw('NaN'), 'parse error', 'line'),
    ('ball_infinity', ['probe', 'ball_diameter_mm'], raw('Infinity'), 'parse error', 'line'),
    ('ball_1e400', ['probe', 'ball_diameter_mm'], raw('1e400'), 'too large', 'line'),
    ('ball_zero', ['probe', 'ball_diameter_mm'], 0, 'ball_diameter_mm', 'line'),
    ('ball_negative', ['probe', 'ball_diameter_mm'], -6.0, 'ball_diameter_mm', 'line'),
    ('ball_huge', ['probe', 'ball_diameter_mm'], 1e308, 'ball_diameter_mm', 'line'),
    ('ball_string', ['probe', 'ball_diameter_mm'], '6', 'ball_diameter_mm', 'line'),
    ('ball_null', ['probe', 'ball_diameter_mm'], None, 'ball_diameter_mm', 'line'),
    ('ball_array', ['probe', 'ball_diameter_mm'], [6.0], 'ball_diameter_mm', 'line'),
    ('ball_missing', ['probe', 'ball_diameter_mm'], DEL, 'ball_diameter_mm', 'line'),
    ('stylus_zero', ['probe', 'stylus_length_mm'], 0.0, 'stylus_length_mm', 'line'),
    ('stylus_negative', ['probe', 'stylus_length_mm'], -50.0, 'stylus_length_mm', 'line'),
    ('repeatability_zero', ['probe', 'repeatability_um'], 0.0, 'repeatability_um', 'line'),
    ('repeatability_negative', ['probe', 'repeatability_um'], -0.7, 'repeatability_um', 'line'),
    ('repeatability_1e308', ['probe', 'repeatability_um'], 1e308, 'repeatability_um', 'line'),
    ('body_clearance_negative', ['probe', 'body_clearance_mm'], -5.0, 'body_clearance_mm', 'line'),
    ('tool_number_1e308', ['probe', 'tool_number'], 1e308, 'tool_number', 'line'),
    ('tool_number_fraction', ['probe', 'tool_number'], 1.5, 'tool_number', 'line'),
    ('tool_number_negative', ['probe', 'tool_number'], -1, 'tool_number', 'line'),
    ('stroke_x_inverted', ['strokes', 'X'], [625.0, -625.0], 'X', 'line'),
    ('stroke_x_empty_range', ['strokes', 'X'], [10.0, 10.0], 'X', 'line'),
    ('stroke_x_one_value', ['strokes', 'X'], [625.0], 'X', 'line'),
    ('stroke_x_three_values', ['strokes', 'X'], [-625.0, 0.0, 625.0], 'X', 'line'),
    ('stroke_x_strings', ['strokes', 'X'], ['-625', '625'], 'X', 'line'),
    ('stroke_y_missing', ['strokes', 'Y'], DEL, 'Y', 'line'),
    ('stroke_z_huge', ['strokes', 'Z'], [-1e300, 1e300], 'Z', 'line'),
    ('stroke_a_inverted', ['rotary_axes', 'A', 'stroke_deg'], [20.0, -110.0], 'stroke_deg', 'line'),
    ('stroke_a_nan', ['rotary_axes', 'A', 'stroke_deg'], [raw('NaN'), 20.0], 'parse error', 'line'),
    ('rotary_a_missing', ['rotary_axes', 'A'], DEL, 'A', 'line'),
    ('controller_sign_fraction', ['rotary_axes', 'A', 'controller_sign'], 1.5, 'controller_sign', 'line'),
    ('controller_sign_zero', ['rotary_axes', 'A', 'controller_sign'], 0, 'controller_sign', 'line'),
    ('dialect_sign_two', ['rotary_axes', 'C', 'dialect_sign', 'linuxcnc'], 2, 'linuxcnc', 'line'),
    ('continuous_string', ['rotary_axes', 'C', 'continuous'], 'yes', 'continuous', 'line'),
    ('kinematics_unknown', ['kinematics'], 'table_xy', 'kinematics', 'line'),
    ('kinematics_number', ['kinematics'], 3, 'kinematics', 'line'),
    ('kinematics_missing', ['kinematics'], DEL, 'kinematics', 'line'),
    ('units_cm', ['units'], 'cm', 'units', 'line'),
    ('format_wrong', ['format'], 'rotacal-machine/9', 'format', 'line'),
    ('format_number', ['format'], 1, 'format', 'line'),
    ('table_diameter_zero', ['table_diameter_mm'], 0.0, 'table_diameter_mm', 'line'),
    ('feed_probing_zero', ['feeds', 'probing_mm_min'], 0.0, 'probing_mm_min', 'line'),
    ('feed_rapid_negative', ['feeds', 'rapid_mm_min'], -20000.0, 'rapid_mm_min', 'line'),
    ('feed_rotary_huge', ['feeds', 'rotary_deg_min'], 1e308, 'rotary_deg_min', 'line'),
    ('clearance_negative', ['clearance_mm'], -10.0, 'clearance_mm', 'line'),
    ('approach_zero', ['approach_mm'], 0.0, 'approach_mm', 'line'),
    ('overtravel_negative', ['overtravel_mm'], -2.0, 'overtravel_mm', 'line'),
    ('artefact_type_unknown', ['artefact', 'type'], 'pyramid', 'type', 'line'),
    ('artefact_size_negative', ['artefact', 'size_mm'], [100.0, -100.0, 150.0], 'size_mm', 'line'),
    ('artefact_top_two_values', ['artefact', 'top_centre_w_mm'], [0.0, -200.0], 'top_centre_w_mm', 'line'),
    ('probe_not_object', ['probe'], 6.0, 'probe', 'line'),
    ('strokes_array', ['strokes'], [[-625, 625]], 'strokes', 'line'),
]
for name, path, value, frag, locus in machine_cases:
    add('machine', name + '.json', dump(setp(M, path, value)), T_MACHINE, 1, frag, locus)
text = dump(M)
add('machine', 'empty.json', '', T_MACHINE, 1, 'parse error', 'line')
add('machine', 'truncated.json', text[: len(text) // 2], T_MACHINE, 1, 'parse error', 'line')
add('machine', 'trailing_garbage.json', text + '}\n', T_MACHINE, 1, 'parse error', 'line')
add('machine', 'top_level_array.json', '[' + text + ']\n', T_MACHINE, 1, 'JSON object', 'line')
add('machine', 'top_level_string.json', '"rotacal-machine/1"\n', T_MACHINE, 1, 'JSON object', 'line')
add('machine', 'binary.json', bytes(range(256)) * 4, T_MACHINE, 1, 'parse error', 'line')
add('machine', 'deep_nesting.json', '{"format": "rotacal-machine/1", "x": ' + '[' * 100000 + ']' * 100000 + '}\n',
    T_MACHINE, 1, 'nest', 'line')
huge = text.replace('"strokes": {\n  "X": [\n   -625.0,\n   625.0\n  ]',
                    '"strokes": {\n' + '\n' * 200000 + '  "X": [\n   625.0,\n   -625.0\n  ]')
assert huge != text
add('machine', 'huge_inverted_stroke_at_line_200k.json', huge, T_MACHINE, 1, 'X', 'line')
add('machine', 'huge_string_field.json', dump(setp(M, ['kinematics'], 'x' * 2000000)), T_MACHINE, 1, 'kinematics', 'line')
add('machine', 'utf16.json', text.encode('utf-16'), T_MACHINE, 1, 'parse error', 'line')

# ---------------------------------------------------------------- plans
P = json.loads(rd('small.plan.json'))
T_PLAN_GEN = 'generate --plan {in} --dialect fanuc -o {out}.nc'
T_PLAN_AN = 'analyze --plan {in} --results {base}/small.csv.res --dialect csv --json {out}.json'
def pt(i, key):
    return ['points', i, key]
plan_cases = [
    ('duplicate_id', pt(5, 'id'), 5, 'id', 'line'),
    ('id_negative', pt(3, 'id'), -1, 'id', 'line'),
    ('id_fraction', pt(3, 'id'), 3.5, 'id', 'line'),
    ('id_string', pt(3, 'id'), '4', 'id', 'line'),
    ('id_missing', pt(3, 'id'), DEL, 'id', 'line'),
    ('normal_not_unit', pt(10, 'normal_w'), [0.0, 0.0, 2.0], 'normal_w', 'line'),
    ('normal_zero', pt(10, 'normal_w'), [0.0, 0.0, 0.0], 'normal_w', 'line'),
    ('normal_nan', pt(10, 'normal_w'), [raw('NaN'), 0.0, 1.0], 'parse error', 'line'),
    ('normal_two_values', pt(10, 'normal_w'), [0.0, 1.0], 'normal_w', 'line'),
    ('approach_zero', pt(12, 'approach_m'), [0.0, 0.0, 0.0], 'approach_m', 'line'),
    ('approach_not_unit', pt(12, 'approach_m'), [0.0, 0.0, -3.0], 'approach_m', 'line'),
    ('approach_reversed', pt(0, 'approach_m'), [1.0, 0.0, 0.0], 'approach_m', 'line'),
    ('pose_out_of_stroke', pt(20, 'pose'), {'A': 50.0, 'C': 0.0}, 'stroke', 'line'),
    ('pose_far_out_of_stroke', pt(20, 'pose'), {'A': -200.0, 'C': 0.0}, 'stroke', 'line'),
    ('pose_unknown_axis', pt(20, 'pose'), {'B': 0.0, 'C': 0.0}, 'pose', 'line'),
    ('pose_string', pt(20, 'pose'), {'A': '0', 'C': 0.0}, 'A', 'line'),
    ('trigger_out_of_stroke', pt(7, 'trigger_m_mm'), [5000.0, -225.0, 150.0], 'stroke', 'line'),
    ('trigger_1e400', pt(7, 'trigger_m_mm'), [raw('1e400'), -225.0, 150.0], 'too large', 'line'),
    ('contact_two_values', pt(7, 'contact_w_mm'), [50.0, -225.0], 'contact_w_mm', 'line'),
    ('t_negative', pt(30, 't_s'), -4.0, 't_s', 'line'),
    ('t_huge', pt(30, 't_s'), 1e300, 't_s', 'line'),
    ('points_empty', ['points'], [], 'points', 'line'),
    ('points_missing', ['points'], DEL, 'points', 'line'),
    ('points_object', ['points'], {'1': 1}, 'points', 'line'),
    ('point_not_object', ['points', 4], 17, 'point', 'line'),
    ('format_wrong', ['format'], 'rotacal-plan/2', 'format', 'line'),
    ('cycle_unknown', ['cycle'], 'touch999', 'touch999', 'line'),
    ('cycle_number', ['cycle'], 154, 'cycle', 'line'),
    ('machine_ball_zero', ['machine', 'probe', 'ball_diameter_mm'], 0.0, 'ball_diameter_mm', 'line'),
    ('machine_missing', ['machine'], DEL, 'machine', 'line'),
    ('machine_kinematics_bc', ['machine', 'kinematics'], 'table_bc', 'axis B', 'line'),
    ('index_z_nan', ['index_z_mm'], raw('NaN'), 'parse error', 'line'),
    ('index_z_below_table', ['index_z_mm'], -100.0, 'index_z_mm', 'line'),
    ('option_unknown', ['options', 'bogus'], '1', 'bogus', 'line'),
    ('option_not_number', ['options', 'top_offsets_mm'], 'a,b', 'top_offsets_mm', 'line'),
]
for name, path, value, frag, locus in plan_cases:
    tmpl = T_PLAN_AN if name.startswith(('t_', 'approach_', 'normal_')) and False else T_PLAN_GEN
    add('plan', name + '.json', dump(setp(P, path, value)), tmpl, 1, frag, locus)
for name, path, value, frag, locus in plan_cases[:12]:
    add('plan', 'analyze_' + name + '.json', dump(setp(P, path, value)), T_PLAN_AN, 1, frag, locus)
# a spindle-head machine's plan read as a table cycle's (found by fuzz_plan): refused at its
# kinematics line, not with the kinematics' own message
TP = json.loads(rd('tooltip.plan.json'))
add('plan', 'tooltip_plan_as_touch154.json', dump(setp(TP, ['cycle'], 'touch154')), T_PLAN_GEN, 1, 'spindle-head', 'line')
# more points than the loader takes (kMaxPlanPoints = 10000)
big = copy.deepcopy(P)
p0 = big['points'][0]
big['points'] = [dict(p0, id=i + 1) for i in range(10001)]
add('plan', 'too_many_points.json', json.dumps(big) + '\n', T_PLAN_GEN, 1, '10000', 'line')
S3 = json.loads(rd('spheres3.plan.json'))
pose0 = S3['points'][0]['pose']
s3 = copy.deepcopy(S3)
s3['points'] = [p for p in s3['points'] if p['pose'] != pose0]
add('plan', 'spheres3_pose_without_points.json', dump(s3),
    'analyze --plan {in} --results {base}/small.csv.res --dialect csv --json {out}.json', 1, 'pose', 'line')
s3 = setp(S3, ['points', 2, 'sphere', 'radius_mm'], 0.0)
add('plan', 'spheres3_radius_zero.json', dump(s3), T_PLAN_GEN, 1, 'radius_mm', 'line')

# ---------------------------------------------------------------- truth
TR = json.loads(rd('truth.json'))
T_TRUTH = 'simulate --plan {base}/small.plan.json --truth {in} --dialect csv -o {out}.csv'
truth_cases = [
    ('value_nan', ['location_errors', 'dx_AY', 'value'], raw('NaN'), 'parse error', 'line'),
    ('value_1e400', ['location_errors', 'dx_AY', 'value'], raw('1e400'), 'too large', 'line'),
    ('value_string', ['location_errors', 'dx_AY', 'value'], '14.6', 'dx_AY', 'line'),
    ('value_huge', ['location_errors', 'a_AY', 'value'], 1e300, 'mdeg', 'line'),
    ('unit_unknown', ['location_errors', 'dx_AY', 'unit'], 'furlong', 'unit', 'line'),
    ('unit_angle_for_length', ['location_errors', 'dx_AY', 'unit'], 'mdeg', 'unit', 'line'),
    ('parameter_unknown', ['location_errors', 'dq_XX'], {'value': 1.0, 'unit': 'um'}, 'dq_XX', 'line'),
    ('parameter_of_bc', ['location_errors', 'dx_BY'], {'value': 1.0, 'unit': 'um'}, 'dx_BY', 'line'),
    ('location_errors_array', ['location_errors'], [1, 2], 'location_errors', 'line'),
    ('entry_number', ['location_errors', 'dy_AY'], 23.2, 'dy_AY', 'line'),
    ('format_wrong', ['format'], 'rotacal-report/1', 'format', 'line'),
    ('setup_two_values', ['setup_error', 'translation_mm'], [0.5, 0.5], 'translation_mm', 'line'),
    ('setup_huge', ['setup_error', 'rotation_mrad'], [0.0, 0.0, 1e300], 'rotation_mrad', 'line'),
    ('form_error_string', ['form_error', 'top', 'tilt_v_mrad'], 'two', 'tilt_v_mrad', 'line'),
    ('noise_negative', ['probe_noise_um'], -1.0, 'probe_noise_um', 'line'),
]
for name, path, value, frag, locus in truth_cases:
    add('truth', name + '.json', dump(setp(TR, path, value)), T_TRUTH, 1, frag, locus)
add('truth', 'empty.json', '', T_TRUTH, 1, 'parse error', 'line')
add('truth', 'not_json.json', 'dx_AY = 14.6 um\n', T_TRUTH, 1, 'parse error', 'line')

# ---------------------------------------------------------------- contributors
C = json.loads(rd('contributors.json'))
T_CONTRIB = 'uncertainty --plan {base}/small.plan.json --contributors {in} --runs 10 --json {out}.json'
contrib_cases = [
    ('u_1e308', ['contributors', 'probe_repeatability', 'u'], 1e308, 'u', 'line'),
    ('u_negative', ['contributors', 'E_xx_rand', 'u'], -2.0, 'u', 'line'),
    ('u_nan', ['contributors', 'E_xx_rand', 'u'], raw('NaN'), 'parse error', 'line'),
    ('u_string', ['contributors', 'S_xy', 'u'], '3', 'u', 'line'),
    ('u_missing', ['contributors', 'S_xy', 'u'], DEL, 'u', 'line'),
    ('unit_unknown', ['contributors', 'S_xy', 'unit'], 'parsec', 'unit', 'line'),
    ('unit_wrong_kind', ['contributors', 'E_xx_lin', 'unit'], 'um', 'unit', 'line'),
    ('id_unknown', ['contributors', 'cosmic_rays'], {'u': 1.0, 'unit': 'um'}, 'cosmic_rays', 'line'),
    ('contributors_array', ['contributors'], [], 'contributors', 'line'),
    ('contributors_missing', ['contributors'], DEL, 'contributors', 'line'),
    ('entry_number', ['contributors', 'E_yy_rand'], 2.0, 'E_yy_rand', 'line'),
    ('format_wrong', ['format'], 'rotacal-truth/1', 'format', 'line'),
    ('node_spacing_zero', ['node_spacing_mm'], 0.0, 'node_spacing_mm', 'line'),
    ('node_spacing_negative', ['node_spacing_mm'], -50.0, 'node_spacing_mm', 'line'),
]
for name, path, value, frag, locus in contrib_cases:
    add('contributors', name + '.json', dump(setp(C, path, value)), T_CONTRIB, 1, frag, locus)
add('contributors', 'empty_object.json', '{}\n', T_CONTRIB, 1, 'format', 'line')

# ---------------------------------------------------------------- reports (compensate, history add)
R = json.loads(rd('report.json'))
T_COMP = 'compensate --program {base}/small.linuxcnc.prog --report {in} --dialect linuxcnc -o {out}.ngc'
T_HIST = 'history add {in} --machine-id m1 --db {db}'
LE = ['location_errors']
report_cases = [
    ('location_errors_empty', LE, {}, 'location_errors', 'line', 'both'),
    ('location_errors_missing', LE, DEL, 'location_errors', 'line', 'both'),
    ('location_errors_array', LE, [], 'location_errors', 'line', 'both'),
    ('one_missing', LE + ['dz_AY'], DEL, 'dz_AY', 'line', 'comp'),
    ('a_AY_10_deg', LE + ['a_AY', 'value'], 10000.0, 'a_AY', 'line', 'comp'),
    ('dx_AY_1m', LE + ['dx_AY', 'value'], 1e6, 'dx_AY', 'line', 'comp'),
    ('value_string', LE + ['dx_AY', 'value'], '14', 'value', 'line', 'both'),
    ('value_nan', LE + ['dx_AY', 'value'], raw('NaN'), 'parse error', 'line', 'both'),
    ('value_1e400', LE + ['dx_AY', 'value'], raw('1e400'), 'too large', 'line', 'both'),
    ('unit_unknown', LE + ['dx_AY', 'unit'], 'inch', 'unit', 'line', 'both'),
    ('unit_number', LE + ['dx_AY', 'unit'], 5, 'unit', 'line', 'both'),
    ('entry_number', LE + ['dx_AY'], 14.6, 'value', 'line', 'both'),
    ('parameter_unknown', LE + ['dq_XX'], {'value': 1.0, 'unit': 'um', 'u': 0.1}, 'dq_XX', 'line', 'comp'),
    ('u_negative', LE + ['dx_AY', 'u'], -1.0, 'u', 'line', 'hist'),
    ('u_string', LE + ['dx_AY', 'u'], 'small', 'u', 'line', 'hist'),
    ('residual_negative', ['residual_rms_um'], -0.5, 'residual_rms_um', 'line', 'hist'),
    ('cycle_missing', ['cycle'], DEL, 'cycle', 'line', 'hist'),
    ('format_wrong', ['format'], 'rotacal-diagnosis/1', 'format', 'line', 'both'),
    ('format_missing', ['format'], DEL, 'format', 'line', 'both'),
    ('machine_model_ball_zero', ['machine_model', 'probe', 'ball_diameter_mm'], 0.0, 'ball_diameter_mm', 'line', 'comp'),
    ('machine_model_missing', ['machine_model'], DEL, 'machine_model', 'line', 'comp'),
    ('machine_model_kinematics_unknown', ['machine_model', 'kinematics'], 'hexapod', 'kinematics', 'line', 'comp'),
    ('points_used_negative', ['points_used'], -3, 'points_used', 'line', 'hist'),
]
for name, path, value, frag, locus, where in report_cases:
    body = dump(setp(R, path, value))
    if where in ('comp', 'both'):
        add('report', 'compensate_' + name + '.json', body, T_COMP, 1, frag, locus)
    if where in ('hist', 'both'):
        add('report', 'history_' + name + '.json', body, T_HIST, 1, frag, locus)
add('report', 'compensate_empty.json', '', T_COMP, 1, 'parse error', 'line')
add('report', 'history_empty.json', '', T_HIST, 1, 'parse error', 'line')
add('report', 'history_top_level_array.json', '[]\n', T_HIST, 1, 'format', 'line')

# ---------------------------------------------------------------- NC programs (compensate, check)
PROG = {d: rd(f'small.{d}.prog') for d in ('linuxcnc', 'fanuc', 'siemens', 'haas', 'okuma')}
EXT = {'linuxcnc': 'ngc', 'fanuc': 'nc', 'haas': 'nc', 'siemens': 'mpf', 'okuma': 'min'}
def T_PCOMP(d):
    return 'compensate --program {in} --report {base}/report.json --dialect %s -o {out}.%s' % (d, EXT[d])
def T_PCHECK(d):
    return 'check {in} --dialect %s --machine {base}/machine.json' % d

def insert_after_first_motion(text, line):
    """Puts `line` before the first G0/G00 move of the program (after the header)."""
    lines = text.split('\n')
    for i, l in enumerate(lines):
        if l.startswith(('G0 ', 'G00 ', 'N')) and ('Z' in l or 'X' in l) and not l.startswith('N0'):
            if l.startswith('N') and ' G' not in l:
                continue
            lines.insert(i + 1, line)
            return '\n'.join(lines)
    raise SystemExit('no motion in program')

prog_cases = [
    # dialect, name, inserted line, fragment
    ('linuxcnc', 'arc_g2', 'G2 X10 Y0 I5 J0 F100', 'arc'),
    ('linuxcnc', 'arc_g3', 'G3 X10 Y0 R5 F100', 'arc'),
    ('fanuc', 'arc_g2', 'G02 X10. Y0. R5. F100.', 'arc'),
    ('siemens', 'arc_g2', 'G2 X10 Y0 CR=5 F100', 'arc'),
    ('linuxcnc', 'g93_without_f', 'G93 G1 X10 Y0 Z200', 'G93'),
    ('fanuc', 'g93_without_f', 'G93 G01 X10. Y0. Z200.', 'G93'),
    ('linuxcnc', 'expression_axis', 'G0 X[#1+2] Y0 Z200', 'expression'),
    ('fanuc', 'expression_axis', 'G00 X[#1+2.] Y0. Z200.', 'expression'),
    ('fanuc', 'parameter_axis', 'G00 X#100 Y0. Z200.', 'expression'),
    ('linuxcnc', 'exponent_word', 'G0 X1e2 Y0 Z200', 'X1e2'),
    ('fanuc', 'exponent_word', 'G00 X1E2 Y0. Z200.', 'X1E2'),
    ('linuxcnc', 'unknown_word_ampersand', 'G0 X10 & Y0', '&'),
    ('fanuc', 'tcp_g43_4', 'G43.4 H1', 'G43.4'),
    ('linuxcnc', 'tilted_plane_g68_2', 'G68.2 X0 Y0 Z0 I0 J45 K0', 'G68.2'),
    ('fanuc', 'work_offset_change', 'G55', 'G55'),
    ('linuxcnc', 'g10_offset_change', 'G10 L2 P1 X5', 'G10'),
    ('linuxcnc', 'incremental_rotary', 'G91 G0 A5', 'incremental'),
    ('fanuc', 'a_out_of_stroke', 'G00 A-200.', 'stroke'),
    ('linuxcnc', 'x_out_of_stroke', 'G0 X9999 Y0 Z300', 'stroke'),
    ('siemens', 'trafoori', 'TRAORI', 'TRAORI'),
    ('linuxcnc', 'unclosed_comment', 'G0 X10 (never closed', 'comment'),
    ('fanuc', 'nested_comment', 'G00 X10. (A (B) C)', 'comment'),
    ('linuxcnc', 'already_compensated', '(ROTACAL-COMPENSATED)', 'compensated'),
    ('siemens', 'meas_empty', 'MEAS=1 ', 'MEAS'),
    ('linuxcnc', 'line_1mb', 'G0 X10 Y0 Z300 (' + 'A' * 1048576 + ')', 'long'),
    ('fanuc', 'line_1mb_digits', 'G00 X1' + '0' * 1048576 + '. Y0. Z300.', 'long'),
    ('linuxcnc', 'nul_byte', 'G0 X10\x00 Y0 Z300', 'x00'),
    ('fanuc', 'g28_inside_probe_move', 'G31 X0. Y0. Z0. F100. G28', 'G28'),
    ('linuxcnc', 'inch_switch', 'G20', 'stroke'),
    ('haas', 'arc_g3', 'G03 X10. Y0. R5. F100.', 'arc'),
    ('okuma', 'arc_g2', 'G02 X10. Y0. R5. F100.', 'arc'),
    ('okuma', 'g93_without_f', 'G93 G01 X10. Y0. Z200.', 'G93'),
]
for d, name, line, frag in prog_cases:
    body = insert_after_first_motion(PROG[d], line)
    add('program', f'compensate_{d}_{name}.{EXT[d]}', body, T_PCOMP(d), 1, frag, 'line')
check_cases = [
    ('linuxcnc', 'rapid_through_artefact', 'G0 X0 Y-200 Z100', 'clear'),
    ('fanuc', 'rapid_through_artefact', 'G00 X0. Y-200. Z100.', 'clear'),
    ('linuxcnc', 'x_out_of_stroke', 'G0 X9999', 'stroke'),
    ('linuxcnc', 'arc', 'G2 X10 Y0 I5 J0 F100', 'arc'),
    ('fanuc', 'a_out_of_stroke', 'G00 A-200.', 'stroke'),
    ('linuxcnc', 'g93_without_f', 'G93 G1 X10 Y0 Z200', 'G93'),
    ('linuxcnc', 'line_1mb', 'G0 X10 Y0 Z300 (' + 'A' * 1048576 + ')', 'long'),
    ('siemens', 'unknown_word', 'G0 X10 QQ=5', 'QQ: a name rotacal does not know'),
]
for d, name, line, frag in check_cases:
    body = insert_after_first_motion(PROG[d], line)
    add('program', f'check_{d}_{name}.{EXT[d]}', body, T_PCHECK(d), 1, frag, 'line')
add('program', 'compensate_empty.ngc', '', T_PCOMP('linuxcnc'), 1, 'empty', 'line')
add('program', 'compensate_binary.nc', bytes(range(256)) * 16, T_PCOMP('fanuc'), 1, 'unexpected character', 'line')
add('program', 'check_empty.ngc', '', T_PCHECK('linuxcnc'), 1, 'empty', 'line')

# ---------------------------------------------------------------- results (analyze)
T_RES = lambda d: 'analyze --plan {base}/small.plan.json --results {in} --dialect %s --json {out}.json' % d
RES = {d: rd(f'small.{d}.res') for d in ('csv', 'linuxcnc', 'fanuc', 'haas', 'siemens', 'heidenhain', 'okuma')}
def lines_of(t):
    return t.split('\n')
def first_data(d, lines):
    import re
    for i, l in enumerate(lines):
        if (d == 'csv' and l[:1].isdigit()) or (d != 'csv' and re.match(r'P *1 ', l)):
            return i
    raise SystemExit('no data line in ' + d)
for d, t in RES.items():
    L = lines_of(t)
    i = first_data(d, L)
    variants = {
        'missing_point': L[:i + 3] + L[i + 4:],
        'repeated_point': L[:i + 3] + [L[i + 3]] + L[i + 3:],
        'header_only': L[:i],
        'garbage_number': L[:i + 2] + [L[i + 2].replace('5', 'x', 1)] + L[i + 3:],
        'line_1mb': L[:i + 2] + [L[i + 2] + ' ' * 1048576 + '1'] + L[i + 3:],
    }
    for vname, vl in variants.items():
        add('results', f'{d}_{vname}.txt', '\n'.join(vl), T_RES(d), 1, '', 'line')
    add('results', f'{d}_empty.txt', '', T_RES(d), 1, '', 'line')
    add('results', f'{d}_binary.txt', bytes(range(256)) * 8, T_RES(d), 1, '', 'line')
add('results', 'csv_nan.txt', RES['csv'].replace('\n3,', '\n3,nan,', 1).replace('nan,25,', 'nan,', 1), T_RES('csv'), 1, '', 'line')
add('results', 'csv_wrong_header.txt', RES['csv'].replace('point,x_mm', 'pt,x_mm', 1), T_RES('csv'), 1, 'header', 'line')
add('results', 'csv_extra_point.txt', RES['csv'] + '999,1,2,3,4\n', T_RES('csv'), 1, '999', 'line')
add('results', 'csv_t_negative.txt', RES['csv'].replace(',4.399', ',-4.399', 1), T_RES('csv'), 1, 'clock', 'line')
add('results', 'csv_5mm_chip.txt', RES['csv'].replace('1,53.56', '1,48.56', 1), T_RES('csv'), 1, '', 'line')
RT = rd('rtest.csv')
T_RT = 'analyze --plan {base}/rtest.plan.json --results {in} --dialect csv --json {out}.json'
rl = lines_of(RT)
add('results', 'rtest_wrong_header.csv', RT.replace('pose,', 'pos,', 1), T_RT, 1, 'header', 'line')
add('results', 'rtest_missing_reading.csv', '\n'.join(rl[:3] + rl[4:]), T_RT, 1, 'out of order', 'line')
add('results', 'rtest_nan.csv', RT.replace('-4.5586', 'nan', 1), T_RT, 1, 'not a number', 'line')
add('results', 'rtest_time_backwards.csv', RT.replace('9.078', '1.000', 1), T_RT, 1, 'backwards', 'line')
add('results', 'rtest_empty.csv', '', T_RT, 1, '', 'line')
add('results', 'rtest_pose_id_2e41.csv', '\n'.join(rl[:2] + ['2' + '1' * 41 + rl[2][1:]] + rl[3:]), T_RT, 1,
    'not a pose id', 'line')  # fuzz_rtest_results: undefined int cast
add('results', 'rtest_line_1mb.csv', '\n'.join(rl[:2] + [rl[2] + ',' * 1048576] + rl[3:]), T_RT, 1, '', 'line')
TT = rd('tooltip.csv')
T_TT = 'analyze --plan {base}/tooltip.plan.json --results {in} --dialect csv --json {out}.json'
tl = lines_of(TT)
add('results', 'tooltip_wrong_header.csv', TT.replace('angle_deg', 'angle', 1), T_TT, 1, 'header', 'line')
add('results', 'tooltip_missing_angle.csv', '\n'.join(tl[:3] + tl[4:]), T_TT, 1, '', 'line')
add('results', 'tooltip_wrong_angle.csv', TT.replace('\n10.0000,', '\n11.0000,', 1), T_TT, 1, '', 'line')
add('results', 'tooltip_inf.csv', TT.replace('\n5.0000,0.0000', '\n5.0000,inf', 1), T_TT, 1, '', 'line')
add('results', 'tooltip_empty.csv', '', T_TT, 1, '', 'line')

# ---------------------------------------------------------------- history databases
T_HSHOW = 'history show --machine-id m1 --db {in}'
T_HADD = 'history add {base}/report.json --machine-id m1 --db {in}'
good = rd('history.db', 'rb')
def db_variant(sql):
    tmp = os.path.join(HERE, '_tmp.db')
    with open(tmp, 'wb') as f:
        f.write(good)
    con = sqlite3.connect(tmp)
    con.executescript(sql)
    con.commit()
    con.close()
    with open(tmp, 'rb') as f:
        data = f.read()
    os.remove(tmp)
    return data
con = sqlite3.connect(':memory:')
tables = None
tmp = os.path.join(HERE, '_tmp.db')
with open(tmp, 'wb') as f:
    f.write(good)
c2 = sqlite3.connect(tmp)
schema = c2.execute("select name, sql from sqlite_master where type='table'").fetchall()
c2.close()
os.remove(tmp)
cols = {n: [c.split()[0] for c in s[s.index('(') + 1:s.rindex(')')].split(',') if c.strip() and not c.strip().upper().startswith(('PRIMARY', 'FOREIGN', 'UNIQUE'))] for n, s in schema}
param_table = [n for n in cols if 'param' in n][0]
cal_table = [n for n in cols if n != param_table][0]
ucol = [c for c in cols[param_table] if c.strip('"') == 'u'][0]
vcol = [c for c in cols[param_table] if c.strip('"') == 'value'][0]
for sub, tmpl in (('show', T_HSHOW), ('add', T_HADD)):
    add('history', f'{sub}_garbage.sqlite', b'this is not a database\n' * 100, tmpl, 1, '', 'in')
    add('history', f'{sub}_truncated.sqlite', good[: len(good) // 3], tmpl, 1, '', 'in')
    add('history', f'{sub}_header_only.sqlite', good[:100], tmpl, 1, '', 'in')
    add('history', f'{sub}_text_in_value.sqlite', db_variant(f"update {param_table} set {vcol} = 'abc';"), tmpl, 1, '', 'in')
    add('history', f'{sub}_u_negative.sqlite', db_variant(f"update {param_table} set {ucol} = -1;"), tmpl, 1, '', 'in')
    add('history', f'{sub}_table_dropped.sqlite', db_variant(f"drop table {param_table};"), tmpl, 1, '', 'in')
    add('history', f'{sub}_value_huge.sqlite', db_variant(f"update {param_table} set {vcol} = 1e308;"), tmpl, 1, '', 'in')
    add('history', f'{sub}_json_file.sqlite', rd('report.json'), tmpl, 1, '', 'in')

# ---------------------------------------------------------------- command-line misuse
MT = rd('machine.json')
add('cli', 'plan_output_is_input.json', MT, 'plan --cycle touch154 --machine {in} -o {in}', 2, '', '-')
add('cli', 'generate_output_is_input.json', rd('small.plan.json'), 'generate --plan {in} --dialect fanuc -o {in}', 2, '', '-')
add('cli', 'analyze_json_is_plan.json', rd('small.plan.json'), 'analyze --plan {in} --results {base}/small.csv.res --dialect csv --json {in}', 2, '', '-')
add('cli', 'analyze_json_is_results.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} --dialect csv --json {in}', 2, '', '-')
add('cli', 'analyze_two_outputs_one_file.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} --dialect csv --json {out}.json --text {out}.json', 2, '', '-')
add('cli', 'analyze_offsets_is_json.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} --dialect csv --json {out}.json --offsets {out}.json', 2, '', '-')
add('cli', 'compensate_output_is_program.ngc', PROG['linuxcnc'], 'compensate --program {in} --report {base}/report.json --dialect linuxcnc -o {in}', 2, '', '-')
add('cli', 'simulate_output_is_truth.json', rd('truth.json'), 'simulate --plan {base}/small.plan.json --truth {in} --dialect csv -o {in}', 2, '', '-')
add('cli', 'plan_missing_dir.json', MT, 'plan --cycle touch154 --machine {in} -o {nodir}/plan.json', 1, 'does not exist', 'out')
add('cli', 'generate_missing_dir.json', rd('small.plan.json'), 'generate --plan {in} --dialect fanuc -o {nodir}/p.nc', 1, 'does not exist', 'out')
add('cli', 'analyze_offsets_missing_dir.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} --dialect csv --json {out}.json --offsets {nodir}/off.csv', 1, 'does not exist', 'out')
add('cli', 'plan_readonly_dir.json', MT, 'plan --cycle touch154 --machine {in} -o {rodir}/plan.json', 1, 'not writable', 'out')
add('cli', 'analyze_readonly_dir.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} --dialect csv --json {out}.json --text {rodir}/r.txt', 1, 'not writable', 'out')
add('cli', 'plan_output_is_directory.json', MT, 'plan --cycle touch154 --machine {in} -o {tmp}', 1, 'not a regular file', 'out')
add('cli', 'plan_unknown_cycle.json', MT, 'plan --cycle touch999 --machine {in} -o {out}.json', 2, 'touch999', '-')
add('cli', 'plan_unknown_option.json', MT, 'plan --cycle touch154 --machine {in} --bogus -o {out}.json', 2, 'bogus', '-')
add('cli', 'plan_c_step_wraps.json', MT, 'plan --cycle spheres3 --machine {in} --set c_step_deg=8.4e-08 -o {out}.json', 1, 'c_step_deg', '-')
add('cli', 'plan_c_step_tiny.json', MT, 'plan --cycle spheres3 --machine {in} --set c_step_deg=1e-6 -o {out}.json', 1, 'c_step_deg', '-')
add('cli', 'plan_set_without_value.json', MT, 'plan --cycle touch154 --machine {in} --set top_offsets_mm -o {out}.json', 2, 'top_offsets_mm', '-')
add('cli', 'simulate_noise_nan.json', rd('small.plan.json'), 'simulate --plan {in} --truth {base}/truth.json --noise-um nan --dialect csv -o {out}.csv', 2, 'noise', '-')
add('cli', 'simulate_start_1e300.json', rd('small.plan.json'), 'simulate --plan {in} --truth {base}/truth.json --start-s 1e300 --dialect fanuc -o {out}.txt', 2, 'start', '-')
add('cli', 'generate_dialect_unknown.json', rd('small.plan.json'), 'generate --plan {in} --dialect mazak -o {out}.nc', 2, 'mazak', '-')
add('cli', 'analyze_same_results_twice.csv', RES['csv'], 'analyze --plan {base}/small.plan.json --results {in} {in} --dialect csv --json {out}.json', 2, 'twice', '-')
add('cli', 'history_bad_date.json', rd('report.json'), 'history add {in} --machine-id m1 --db {db} --time 2024-02-31', 2, '2024-02-31', '-')
add('cli', 'uncertainty_runs_zero.json', rd('contributors.json'), 'uncertainty --plan {base}/small.plan.json --contributors {in} --runs 0 --json {out}.json', 2, 'runs', '-')
add('cli', 'uncertainty_runs_huge.json', rd('contributors.json'), 'uncertainty --plan {base}/small.plan.json --contributors {in} --runs 100000000 --json {out}.json', 2, 'runs', '-')
# compensate refuses the dialect before it reads the program: the program's opening lines stand
# for all of it (a whole copy would only repeat the example program).
HEIDENHAIN_HEAD = ''.join(rd('small.heidenhain.prog').splitlines(keepends=True)[:4])
add('cli', 'compensate_dialect_heidenhain.h', HEIDENHAIN_HEAD, 'compensate --program {in} --report {base}/report.json --dialect heidenhain -o {out}.h', 2, 'heidenhain', '-')
add('cli', 'missing_input_file.json', MT, 'plan --cycle touch154 --machine {tmp}/no_such_machine.json -o {out}.json', 1, 'no_such_machine.json', '-')

# ---------------------------------------------------------------- frame (FRAME.json, spaceframe frame_file)
TABLE1 = [[-0.0170, -0.2243, 73.6373], [0.1266, -102.977, 0.1119], [-88.1763, -51.6103, 149.8827],
          [-88.4696, 50.0995, -0.0242], [-2.3838, 101.2081, 150.2041], [86.5175, 51.0002, 0.0012],
          [88.7260, -52.6343, 150.1732]]
FR = {'format': 'rotacal-frame/1', 'source': 'CMM report (corpus)', 'u_um': 1.0,
      'spheres_mm': {str(i + 1): c for i, c in enumerate(TABLE1)}}
T_FRAME = 'plan --cycle spaceframe --machine {base}/machine.json --set phi_list=-90,-45,0 --set frame_file={in} -o {out}.json'
for name, path, value, frag in [
    ('sphere_far', ['spheres_mm', '3'], [-78.1763, -51.6103, 149.8827], 'not a calibration of this frame'),
    ('u_negative', ['u_um'], -1.0, 'u_um'),
    ('u_nan', ['u_um'], raw('NaN'), 'parse error'),
    ('sphere_two_numbers', ['spheres_mm', '5'], [1.0, 2.0], 'sphere 5'),
    ('sphere_text', ['spheres_mm', '2'], ['a', 'b', 'c'], 'sphere 2'),
    ('format_wrong', ['format'], 'rotacal-frame/2', 'rotacal-frame/1'),
    ('source_empty', ['source'], '', 'source'),
]:
    add('frame', name + '.json', dump(setp(FR, path, value)), T_FRAME, 1, frag, 'line')
six = copy.deepcopy(FR)
del six['spheres_mm']['7']
add('frame', 'six_spheres.json', dump(six), T_FRAME, 1, 'seven', 'line')

with open(os.path.join(HERE, 'MANIFEST.tsv'), 'w') as f:
    f.write('# file\tcommand (rotacal arguments; {in} a copy of the file, {out} a fresh output path, {base} '
            'tests/data/bad/base, {db} a copy of base/history.db, {nodir} a missing directory, {rodir} a read-only '
            'one, {tmp} the scratch directory)\texit\tmessage fragment\tnames\n')
    for e in entries:
        f.write('\t'.join(x if x else '-' for x in e) + '\n')
print(len(entries), 'entries')
