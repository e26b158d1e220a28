"""A team over mutual TLS with access control, from the commands: the managers and two
members with the documented configuration (docs/examples/zenoh-tls.json5) and
certificates made here; a member whose certificate the team's CA did not sign, and one
with no certificate, cannot join; the member with a good one does, and the goal is met.

The certificates are generated in ``tmp_path`` (no key in the repository): with the
``cryptography`` package, else the ``openssl`` command; the test skips without either."""

from __future__ import annotations

import datetime
import ipaddress
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
TEAM = ROOT / "tests" / "data" / "transport" / "panels.team.yaml"
EXAMPLE = ROOT / "docs" / "examples" / "zenoh-tls.json5"
NAME = "panels-team"
"""The certificates' common name, as the example's access control allows it."""


def _with_cryptography(folder: Path) -> None:
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = datetime.datetime.now(datetime.timezone.utc)

    def sign(name: str, key, issuer, issuer_key, *, ca: bool):
        builder = (x509.CertificateBuilder()
                   .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, name)]))
                   .issuer_name(issuer).public_key(key.public_key())
                   .serial_number(x509.random_serial_number())
                   .not_valid_before(now - datetime.timedelta(minutes=5))
                   .not_valid_after(now + datetime.timedelta(days=1))
                   .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True))
        if not ca:
            builder = builder.add_extension(x509.SubjectAlternativeName(
                [x509.DNSName("localhost"), x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]),
                critical=False)
        return builder.sign(issuer_key, hashes.SHA256())

    def write(stem: str, key, cert) -> None:
        (folder / f"{stem}.key").write_bytes(key.private_bytes(
            serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption()))
        (folder / f"{stem}.pem").write_bytes(cert.public_bytes(serialization.Encoding.PEM))

    for ca_stem, leaf_stem in (("ca", "team"), ("rogue-ca", "rogue")):
        ca_key = ec.generate_private_key(ec.SECP256R1())
        ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, ca_stem)])
        ca_cert = sign(ca_stem, ca_key, ca_name, ca_key, ca=True)
        key = ec.generate_private_key(ec.SECP256R1())
        write(ca_stem, ca_key, ca_cert)
        write(leaf_stem, key, sign(NAME, key, ca_cert.subject, ca_key, ca=False))


def _with_openssl(folder: Path) -> None:
    def run(*args: str) -> None:
        subprocess.run(["openssl", *args], cwd=folder, check=True, capture_output=True)

    (folder / "leaf.ext").write_text("basicConstraints=critical,CA:FALSE\n"
                                     "subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    for ca, leaf in (("ca", "team"), ("rogue-ca", "rogue")):
        run("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256", "-nodes",
            "-keyout", f"{ca}.key", "-out", f"{ca}.pem", "-days", "1", "-subj", f"/CN={ca}")
        run("req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:P-256", "-nodes",
            "-keyout", f"{leaf}.key", "-out", f"{leaf}.csr", "-subj", f"/CN={NAME}")
        run("x509", "-req", "-in", f"{leaf}.csr", "-CA", f"{ca}.pem", "-CAkey", f"{ca}.key",
            "-CAcreateserial", "-out", f"{leaf}.pem", "-days", "1", "-extfile", "leaf.ext")


def _certificates(folder: Path) -> None:
    folder.mkdir()
    try:
        _with_cryptography(folder)
    except ImportError:
        if shutil.which("openssl") is None:
            pytest.skip("no way to make certificates here: neither the cryptography "
                        "package (pip install '.[test]') nor the openssl command")
        _with_openssl(folder)


def _shary(*args: str, cwd: Path, **kw) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "shary", *args], cwd=cwd, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env={**os.environ, "COLUMNS": "200"}, **kw)


def test_a_team_over_mutual_tls_admits_only_the_certificates_of_its_ca(tmp_path: Path) -> None:
    from test_transport import free_port

    _certificates(tmp_path / "certs")
    shutil.copy(EXAMPLE, tmp_path / "zenoh-tls.json5")
    rogue = EXAMPLE.read_text().replace("certs/team.", "certs/rogue.")
    (tmp_path / "rogue.json5").write_text(rogue)
    no_certificate = "\n".join(line for line in EXAMPLE.read_text().splitlines()
                               if "connect_" not in line)
    (tmp_path / "anonymous.json5").write_text(no_certificate)
    endpoint = f"tls/127.0.0.1:{free_port()}"
    iva = None
    up = _shary("team", "up", str(TEAM), "--listen", endpoint, "--zenoh-config",
                "zenoh-tls.json5", "--remote", "IVA", "--log-dir", "logs", "--wait", "90s",
                "--json", cwd=tmp_path, start_new_session=True)
    try:
        for config in ("rogue.json5", "anonymous.json5"):
            refused = _shary("agent", "IVA", "--team", str(TEAM), "--connect", endpoint,
                             "--zenoh-config", config, cwd=tmp_path)
            _, err = refused.communicate(timeout=60)
            assert refused.returncode == 2, err
            assert f"cannot join the team at {endpoint}" in err and "Traceback" not in err
        iva = _shary("agent", "IVA", "--team", str(TEAM), "--connect", endpoint,
                     "--zenoh-config", "zenoh-tls.json5", "--log-dir", "logs", cwd=tmp_path)
        out, err = up.communicate(timeout=120)
        iva.communicate(timeout=30)
    finally:
        if up.poll() is None:
            os.killpg(up.pid, 9)  # the managers and the members they started
            up.wait()
        if iva is not None and iva.poll() is None:
            iva.kill()
            iva.wait()
    assert up.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "done" and result["lost"] == []
    assert iva.returncode == 0
    assert sorted(p.name for p in (tmp_path / "logs").glob("*.sqlite")) == [
        "EVA1.sqlite", "EVA2.sqlite", "IVA.sqlite", "managers.sqlite"]
