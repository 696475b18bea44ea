"""Fleet key files (no rospy): the fleet key (``make_key``), the key pair of each role
derived from it, and role key files (``make_key --role``): what
:mod:`server_select.core.trust.seal` signs and checks with.

The fleet key is 32 random bytes, hex, in a file of mode 0600. Each role's Ed25519 key
pair is derived from it with HKDF-SHA256 (info ``server_select role <role>``), so every
node given the fleet key holds every role. A role key file holds one role's private key
and every role's public key: a node given it checks every message and signs only as its
role (``observer``: checks only, for viewers).
"""

import argparse
import hashlib
import hmac
import os
import stat

KEY_BYTES = 32            # what make_key writes, and what a fleet key must have
ROLES = ('manager', 'server', 'robot')
OBSERVER = 'observer'     # a role key file that checks and signs nothing (top, report)


class KeyFileError(ValueError):
    """A key file that cannot be used (named, with what to do)."""


def _signing():
    """libsodium's Ed25519 (PyNaCl; imported when a key is used: nodes without one need
    none). Twice as fast as OpenSSL's here: sign 25 us, verify 66 us (55 / 131)."""
    from nacl import signing
    return signing


def _write_private(path, text):
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, 'w') as stream:
        stream.write(text)


def make_key(path, random=os.urandom):
    """Write a new fleet key (``KEY_BYTES`` random bytes, hex) to ``path``, readable by its
    owner only; refuses to overwrite a file."""
    _write_private(path, random(KEY_BYTES).hex() + '\n')


def _read_private(path):
    """The text of key file ``path`` (KeyFileError when missing or not private)."""
    try:
        mode = os.stat(path).st_mode
        with open(path) as stream:
            text = stream.read().strip()
    except OSError as error:
        raise KeyFileError('cannot read fleet key %s: %s' % (path, error.strerror))
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise KeyFileError('fleet key %s can be read or written by others (mode %03o): '
                           'chmod 600 %s' % (path, stat.S_IMODE(mode), path))
    return text


def _hex(text, path, what='fleet key'):
    try:
        return bytes.fromhex(text)
    except ValueError:
        raise KeyFileError('%s %s is not hex text (make one with make_key)' % (what, path))


def copy_key(source, path):
    """Put the key of file ``source`` at ``path`` in one step, mode 0600 (a node reading
    ``path`` meanwhile reads the old key or the new one, whole: a rotation's files)."""
    text = _read_private(source)
    partial = '%s.%d.part' % (path, os.getpid())
    fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, 'w') as stream:
        stream.write(text + '\n')
    os.replace(partial, path)


def load_key(path):
    """The fleet key in ``path`` (hex text, as :func:`make_key` writes it). Refused
    (:class:`KeyFileError`) when missing, readable or writable by group or others, not hex, or
    not ``KEY_BYTES`` long (a key cut or copied in part would be another fleet's: every
    peer would then refuse this node's signatures, and nothing here would say why)."""
    key = _hex(_read_private(path), path)
    if len(key) != KEY_BYTES:
        raise KeyFileError('fleet key %s has %d bytes (%d hex characters), not %d (%d, as '
                           'make_key writes it): was it cut or copied in part?'
                           % (path, len(key), 2 * len(key), KEY_BYTES, 2 * KEY_BYTES))
    return key


def role_seed(fleet_key, role):
    """The 32-byte private key of ``role``, derived from the fleet key (HKDF-SHA256)."""
    return hkdf_sha256(fleet_key, b'server_select role ' + role.encode('ascii'))


def hkdf_sha256(key, info, length=32, salt=b''):
    """HKDF-SHA256 (RFC 5869) of ``key``: ``length`` bytes for ``info``."""
    prk = hmac.new(salt or bytes(hashlib.sha256().digest_size), key, hashlib.sha256).digest()
    out, block = b'', b''
    for counter in range(1, -(-length // hashlib.sha256().digest_size) + 1):
        block = hmac.new(prk, block + info + bytes([counter]), hashlib.sha256).digest()
        out += block
    return out[:length]


class Keys(object):
    """One fleet's keys as a node holds them: every role's public key, and the private key
    of the role the node signs as (``role``; None for a node that only checks)."""

    def __init__(self, public, role=None, private=None):
        self.public, self.role, self.private = public, role, private

    def fingerprint(self):
        """12 hex characters naming the fleet these keys belong to (of every role's public
        key: a fleet key and the role key files made from it say the same), for an
        operator comparing nodes; it tells nothing of the private keys."""
        digest = hashlib.sha256()
        for role in ROLES:
            digest.update(bytes(self.public[role]))
        return digest.hexdigest()[:12]

    @classmethod
    def from_fleet(cls, fleet_key, role=None):
        """Derived from the fleet key; signing as ``role`` (None: check only)."""
        private = dict((r, _signing().SigningKey(role_seed(fleet_key, r))) for r in ROLES)
        return cls(dict((r, k.verify_key) for r, k in private.items()), role,
                   private.get(role))


def role_file_text(keys):
    """The text of the key file of ``keys``' role (no role: an observer's, public keys
    only)."""
    role = keys.role or OBSERVER
    lines = ['# server_select role key: signs as %s, checks every role (make_key --role)'
             % role, 'role %s' % role]
    if keys.private is not None:
        lines.append('sign %s' % bytes(keys.private).hex())
    lines += ['%s %s' % (r, bytes(keys.public[r]).hex()) for r in ROLES]
    return '\n'.join(lines) + '\n'


def make_role_key(fleet_path, role, path):
    """Write ``role``'s key file (its private key and every role's public key, derived
    from the fleet key in ``fleet_path``; ``observer``: public keys only) to ``path``,
    mode 0600."""
    if role not in ROLES + (OBSERVER,):
        raise KeyFileError('no role %r (one of %s)' % (role, ', '.join(ROLES + (OBSERVER,))))
    keys = Keys.from_fleet(load_key(fleet_path), None if role == OBSERVER else role)
    _write_private(path, role_file_text(keys))


def _role_file(text, path):
    """Keys of a role key file's ``text``."""
    signing, fields = _signing(), {}
    for line in text.splitlines():
        if line.strip() and not line.startswith('#'):
            name, _, value = line.partition(' ')
            fields[name] = value.strip()
    missing = [r for r in ('role',) + ROLES if r not in fields]
    if missing or fields['role'] not in ROLES + (OBSERVER,):
        raise KeyFileError('key file %s is neither a fleet key nor a role key (no %s)'
                           % (path, ', '.join(missing) or 'known role'))
    try:
        public = dict((r, signing.VerifyKey(_hex(fields[r], path)))
                      for r in ROLES)
        private = signing.SigningKey(_hex(fields['sign'], path)) \
            if 'sign' in fields else None
    except ValueError as error:
        raise KeyFileError('role key %s: %s' % (path, error))
    role = fields['role'] if private is not None else None
    return Keys(public, role, private)


def load_keys(path, role=None):
    """The :class:`Keys` of key file ``path`` for a node signing as ``role`` (None: it
    checks only): a fleet key (every role derived from it), or a role key file of that
    role (of any role, or ``observer``, when ``role`` is None)."""
    text = _read_private(path)
    if len(text.split()) == 1:
        return Keys.from_fleet(load_key(path), role)
    keys = _role_file(text, path)
    if role is not None and keys.role != role:
        raise KeyFileError('key file %s signs as %s, and this node publishes as %s: give it '
                           'the %s key (make_key --role %s --fleet FLEET_KEY FILE)' % (
                               path, keys.role or 'nobody (observer)', role, role, role))
    return keys if role is not None else Keys(keys.public)


def make_key_cli(argv=None):
    """``make_key FILE``: a new fleet key in FILE; ``make_key --role ROLE --fleet KEY FILE``:
    ROLE's key file, derived from fleet key KEY (mode 0600; an existing file is kept)."""
    parser = argparse.ArgumentParser(
        prog='make_key', description='Write a new fleet key (%d random bytes, hex) to FILE, '
        'readable by its owner only; with --role, the key file of one role derived from '
        'the fleet key (its private key and every role\'s public key). Give each node its '
        'role\'s file, or every node the fleet key (~fleet_key, or fleet_key:= of the '
        'launch files).' % KEY_BYTES)
    parser.add_argument('file')
    parser.add_argument('--role', choices=ROLES + (OBSERVER,),
                        help='write this role\'s key file (observer: checks, signs nothing)')
    parser.add_argument('--fleet', metavar='KEY', help='the fleet key (with --role)')
    args = parser.parse_args(argv)
    if bool(args.role) != bool(args.fleet):
        parser.error('--role and --fleet go together')
    try:
        if args.role:
            make_role_key(args.fleet, args.role, args.file)
        else:
            make_key(args.file)
    except KeyFileError as error:
        parser.exit(1, 'make_key: %s\n' % error)
    except OSError as error:
        parser.exit(1, 'make_key: %s: %s\n' % (args.file, error.strerror))
    print('%s key written to %s (mode 0600)' % (args.role or 'fleet', args.file))
    return 0
