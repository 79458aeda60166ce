"""Key material for the dev cluster: a CA, the apiserver's serving cert, SA keys and tokens.

Everything is made with the ``openssl`` command-line tool (present on every Debian/Ubuntu image;
the ``cryptography`` package is not a project dependency). Keys are ECDSA P-256: generating them
takes milliseconds, and both Go's TLS stack and the service-account token signer accept them.
Files are created once per cluster root and reused on the next ``up``, so a restart keeps the
kubeconfig valid.
"""

from __future__ import annotations

import dataclasses
import secrets
import shutil
import subprocess
from collections.abc import Mapping
from pathlib import Path

from simtest_operator.errors import ToolchainError

SERVING_SANS = (
    "IP:127.0.0.1",
    "DNS:localhost",
    "DNS:kubernetes",
    "DNS:kubernetes.default",
    "DNS:kubernetes.default.svc",
    "DNS:kubernetes.default.svc.cluster.local",
    "IP:10.96.0.1",
)
"""Names the apiserver's serving certificate is valid for (loopback plus in-cluster names)."""

USERS: Mapping[str, tuple[str, tuple[str, ...]]] = {
    "admin": ("admin", ("system:masters",)),
    "kube-controller-manager": ("system:kube-controller-manager", ()),
    "kube-scheduler": ("system:kube-scheduler", ()),
    "kwok": ("kwok-controller", ("system:masters",)),
    "kueue": ("kueue-controller", ("system:masters",)),
}
"""Token users by client: (user name, groups). The controller-manager and the scheduler get the
user names that Kubernetes' bootstrap RBAC policy already binds, so RBAC is exercised for real."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Pki:
    """Paths of the generated files and the bearer token of each client."""

    directory: Path
    tokens: Mapping[str, str]
    """Bearer token by client name (keys of :data:`USERS`)."""

    @property
    def ca_cert(self) -> Path:
        return self.directory / "ca.crt"

    @property
    def ca_key(self) -> Path:
        return self.directory / "ca.key"

    @property
    def serving_cert(self) -> Path:
        return self.directory / "apiserver.crt"

    @property
    def serving_key(self) -> Path:
        return self.directory / "apiserver.key"

    @property
    def sa_key(self) -> Path:
        """Service-account token signing key (private)."""
        return self.directory / "sa.key"

    @property
    def sa_pub(self) -> Path:
        """Service-account token verification key (public)."""
        return self.directory / "sa.pub"

    @property
    def token_file(self) -> Path:
        """The apiserver's ``--token-auth-file`` (CSV: token,user,uid,"groups")."""
        return self.directory / "tokens.csv"


def _openssl(*args: str, cwd: Path) -> None:
    exe = shutil.which("openssl")
    if exe is None:
        raise ToolchainError("the openssl command is needed to create the dev-cluster certificates")
    result = subprocess.run([exe, *args], cwd=cwd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise ToolchainError(f"openssl {args[0]} failed: {result.stderr.strip()}")


def _ec_key(path: Path) -> None:
    _openssl(
        "genpkey",
        "-algorithm",
        "EC",
        "-pkeyopt",
        "ec_paramgen_curve:P-256",
        "-out",
        path.name,
        cwd=path.parent,
    )
    path.chmod(0o600)


def _write_tokens(path: Path) -> dict[str, str]:
    tokens = {client: secrets.token_urlsafe(24) for client in USERS}
    lines = []
    for client, (user, groups) in USERS.items():
        group_field = f',"{",".join(groups)}"' if groups else ""
        lines.append(f"{tokens[client]},{user},{user}{group_field}")
    path.write_text("\n".join(lines) + "\n")
    path.chmod(0o600)
    return tokens


def _read_tokens(path: Path) -> dict[str, str] | None:
    by_user = {}
    for line in path.read_text().splitlines():
        token, user = line.split(",")[:2]
        by_user[user] = token
    if any(user not in by_user for user, _ in USERS.values()):
        return None
    return {client: by_user[user] for client, (user, _) in USERS.items()}


def ensure_pki(directory: Path) -> Pki:
    """Create the CA, serving cert, SA key pair and token file unless they exist; return them."""
    directory.mkdir(parents=True, exist_ok=True)
    pki = Pki(directory=directory, tokens={})
    if not (pki.ca_cert.exists() and pki.ca_key.exists()):
        _ec_key(pki.ca_key)
        _openssl(
            "req",
            "-x509",
            "-new",
            "-key",
            pki.ca_key.name,
            "-out",
            pki.ca_cert.name,
            "-days",
            "3650",
            "-subj",
            "/CN=simtest-dev-cluster-ca",
            "-addext",
            "basicConstraints=critical,CA:TRUE",
            "-addext",
            "keyUsage=critical,keyCertSign,cRLSign,digitalSignature",
            cwd=directory,
        )
        pki.serving_cert.unlink(missing_ok=True)
    if not (pki.serving_cert.exists() and pki.serving_key.exists()):
        _ec_key(pki.serving_key)
        ext = directory / "apiserver.ext"
        ext.write_text(
            "basicConstraints=CA:FALSE\n"
            "keyUsage=critical,digitalSignature,keyEncipherment\n"
            "extendedKeyUsage=serverAuth\n"
            f"subjectAltName={','.join(SERVING_SANS)}\n"
        )
        _openssl(
            "req",
            "-new",
            "-key",
            pki.serving_key.name,
            "-out",
            "apiserver.csr",
            "-subj",
            "/CN=kube-apiserver",
            cwd=directory,
        )
        _openssl(
            "x509",
            "-req",
            "-in",
            "apiserver.csr",
            "-CA",
            pki.ca_cert.name,
            "-CAkey",
            pki.ca_key.name,
            "-CAcreateserial",
            "-out",
            pki.serving_cert.name,
            "-days",
            "3650",
            "-extfile",
            ext.name,
            cwd=directory,
        )
    if not (pki.sa_key.exists() and pki.sa_pub.exists()):
        _ec_key(pki.sa_key)
        _openssl("pkey", "-in", pki.sa_key.name, "-pubout", "-out", pki.sa_pub.name, cwd=directory)
    tokens = _read_tokens(pki.token_file) if pki.token_file.exists() else None
    if tokens is None:
        tokens = _write_tokens(pki.token_file)
    return dataclasses.replace(pki, tokens=tokens)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClientCert:
    """A client certificate signed by the cluster CA (PEM files)."""

    cert: Path
    key: Path


def ensure_client_cert(pki: Pki, *, name: str, user: str, groups: tuple[str, ...]) -> ClientCert:
    """A client certificate for ``user`` in ``groups`` (CN and O), made once and reused.

    A kubelet authenticates as ``system:node:<node>`` in ``system:nodes`` with such a certificate,
    exactly as on a kubeadm node, so the apiserver's Node authorizer and NodeRestriction admission
    apply to the dev cluster's real nodes too.
    """
    folder = pki.directory / "clients"
    folder.mkdir(parents=True, exist_ok=True)
    issued = ClientCert(cert=folder / f"{name}.crt", key=folder / f"{name}.key")
    if issued.cert.exists() and issued.key.exists():
        return issued
    _ec_key(issued.key)
    subject = "".join(f"/O={group}" for group in groups) + f"/CN={user}"
    ext = folder / f"{name}.ext"
    ext.write_text(
        "basicConstraints=CA:FALSE\n"
        "keyUsage=critical,digitalSignature,keyEncipherment\n"
        "extendedKeyUsage=clientAuth\n"
    )
    _openssl(
        "req", "-new", "-key", issued.key.name, "-out", f"{name}.csr", "-subj", subject, cwd=folder
    )
    _openssl(
        "x509",
        "-req",
        "-in",
        f"{name}.csr",
        "-CA",
        str(pki.ca_cert),
        "-CAkey",
        str(pki.ca_key),
        "-CAcreateserial",
        "-out",
        issued.cert.name,
        "-days",
        "3650",
        "-extfile",
        ext.name,
        cwd=folder,
    )
    return issued
